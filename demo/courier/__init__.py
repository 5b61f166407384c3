"""The delivery demo's robot programs: the mission, the link, and the experiment's two designs.

- `geometry`: the odometry pose (`Pose`) and the sonar ring, as both designs read them;
- `link`: the link to the robot (`Link`: waits, skill switching, parameters, values);
- `mission`: the map's mission and the task's stops, the skills and their parameters, and
  what both designs read the building with alike;
- `sequenced`: the sequencer, the paper's way (`sequenced.delivery`: the mission's narrative,
  phase by phase, over `sequenced.routes` and `sequenced.behaviours`);
- `reactive`: the reactive robot, a rule list run every cycle (`reactive.rules`, over
  `reactive.route`, `reactive.car` and `reactive.state`);
- `main`: the program `situate demo` runs (demo/deliver.py).

Each module imports only those listed before it (`sequenced` and `reactive` never each
other), and `main` both designs: no module imports one that imports it back.
"""
