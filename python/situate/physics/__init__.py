"""The physics robot: the delivery robot in MuJoCo, in the building of a map file, as a ROS 2 robot.

`Building` reads a map file with the 2-D simulator's own loader; `PhysicsWorld` builds it in
MuJoCo with a differential-drive base that has mass, motors with torque limits and friction,
a sonar ring with the sonar's cone and a barcode reader with line of sight; `PhysicsNode` puts
it behind a ROS 2 node over rmw_zenoh (``/clock``, ``odom``, ``/tf``, ``sonar``, ``cmd_vel``),
so that situate drives it as it drives any ROS 2 robot: through its ROS 2 bridge, on ROS time.
Run it with ``python -m situate.physics MAP`` (``--help``). What it does and does not do yet:
docs/physics.md. Needs the ``physics`` extra (``pip install 'situate[physics]'``).
"""

from situate.physics.building import Building
from situate.physics.model import BaseSpec
from situate.physics.world import Odometry, PhysicsWorld, Pose, SonarSpec

__all__ = ["BaseSpec", "Building", "Odometry", "PhysicsWorld", "Pose", "SonarSpec"]
