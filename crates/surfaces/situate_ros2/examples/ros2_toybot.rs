//! The toy robot (sonar ring, wheels, runaway, wander) served by the link on one endpoint, with
//! the ROS 2 bridge on the link's session: what `situate run` will do for a robot file with a
//! `ros2:` section once it is wired in (docs/ros2.md), and what the Python tests check with a
//! real CDR library.
//!
//! `cargo run -p situate_ros2 --example ros2_toybot -- [--listen tcp/127.0.0.1:7447] [--ros2 FILE]`
//! where FILE holds a `ros2:` mapping (default: drive, odom and the sonar ring, and the
//! services). Prints `ready <node token>` once the bridge publishes, and runs until its standard
//! input closes.

use std::io::Read;
use std::time::Duration;

use anyhow::{anyhow, bail, Context};
use situate::manager::{ClockKind, Manager, Request, RobotFile, RobotSpec};
use situate_link::{Link, LinkConfig};
use situate_ros2::{Bridge, Ros2Config};

const ROBOT: &str = "robot: toybot\ncycle: {rate_hz: 50}\ndevices:\n  - {name: sonar, type: toy.sonar}\n  \
    - {name: wheels, type: toy.wheels}\nskills:\n  - {name: runaway, type: toy.runaway}\n  \
    - {name: wander, type: toy.wander}\n";

const ROS2: &str =
    "ros2:\n  services: true\n  topics:\n    - {signal: drive, topic: cmd_vel, type: geometry_msgs/msg/Twist}\n    \
    - {signal: odom, topic: odom, type: nav_msgs/msg/Odometry}\n    \
    - {signal: sonar.range, topic: sonar, type: sensor_msgs/msg/LaserScan, range_max: 4.0}\n";

fn main() -> anyhow::Result<()> {
    let mut listen = situate_link::DEFAULT_ENDPOINT.to_string();
    let mut ros2_text = ROS2.to_string();
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--listen" => listen = args.next().ok_or_else(|| anyhow!("--listen needs an endpoint"))?,
            "--ros2" => {
                let path = args.next().ok_or_else(|| anyhow!("--ros2 needs a file"))?;
                ros2_text = std::fs::read_to_string(&path).with_context(|| format!("reading {path}"))?;
            }
            other => bail!("unknown argument `{other}` (expected --listen ENDPOINT, --ros2 FILE)"),
        }
    }
    let tree = situate::manager::yaml::parse(&ros2_text).map_err(|e| anyhow!("{e}"))?;
    let section = tree.value.get("ros2").ok_or_else(|| anyhow!("the file has no `ros2:` section"))?;
    let ros2 = Ros2Config::from_node(section)?;

    let file = RobotFile::parse("toybot.yaml", ROBOT).map_err(|e| anyhow!("{e:?}"))?;
    let config = LinkConfig { listen: vec![listen], ..LinkConfig::default() };
    let session = Link::open(&config)?;
    let spec = RobotSpec::from_file(&file).clock(ClockKind::Wall);
    let manager = Manager::build(&spec, &situate_toys::registry()).map_err(|e| anyhow!("{e:?}"))?;
    let (handle, join) = manager.spawn(true);
    let link = Link::serve("toybot", handle.clone(), session.clone(), &config)?;
    let bridge = Bridge::start("toybot", handle.clone(), session, &ros2)?;
    println!("ready {}", bridge.node_token());

    let mut sink = Vec::new();
    let _ = std::io::stdin().read_to_end(&mut sink);

    bridge.stop();
    drop(link);
    let _ = handle.request_timeout(Request::Shutdown, Duration::from_secs(5));
    let _ = join.join();
    Ok(())
}
