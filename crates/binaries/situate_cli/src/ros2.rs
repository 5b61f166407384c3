//! The robot file's `ros2:` section as the program wires it (docs/ros2.md): the topics in become
//! devices of the robot before it is built; the bridge (topics out, services, ROS time) starts
//! once the link serves (`robot::start_robot`).

use situate::manager::Registry;
use situate_robotfile::config::ClockKind;
use situate_robotfile::spec::{RobotSpec, SkillSpec};
use situate_ros2::{Inputs, Ros2Config, Ros2Node};

use crate::output::{problem, Exit};

/// Adds `devices` (a topic in's skill and type each) to the robot.
fn add(spec: &mut RobotSpec, registry: &mut Registry, devices: Vec<(SkillSpec, situate::SkillType)>) {
    for (skill, ty) in devices {
        registry.add(ty);
        spec.skills.push(skill);
    }
}

/// The devices of the topics in, added to a robot that is checked or replayed (declarations
/// only: nothing subscribes; a replay plays their signals back).
pub(crate) fn add_devices(spec: &mut RobotSpec, registry: &mut Registry, ros2: Option<&Ros2Config>) {
    if let Some(config) = ros2 {
        let devices = situate_ros2::inputs::devices(&spec.robot, config);
        add(spec, registry, devices);
    }
}

/// Declares the ROS 2 node on the link's `session` and subscribes to the topics in, adding their
/// devices to the robot; with `use_sim_time`, the robot's clock is the simulated one, stepped by
/// `/clock`. Without a session (`--no-link`) the devices are there and write nothing. The node
/// and its subscriptions, for the bridge.
pub(crate) fn declare(
    spec: &mut RobotSpec,
    registry: &mut Registry,
    ros2: Option<&Ros2Config>,
    session: Option<&zenoh::Session>,
) -> anyhow::Result<Option<(Ros2Node, Inputs)>> {
    let Some(config) = ros2 else { return Ok(None) };
    if config.use_sim_time {
        spec.clock = ClockKind::Simulated;
    }
    let Some(session) = session else {
        add_devices(spec, registry, ros2);
        return Ok(None);
    };
    let failed = |e: situate_ros2::Ros2Error| problem(Exit::Failure, format!("starting the ROS 2 node: {e}"));
    let node = Ros2Node::declare(&spec.robot, session.clone(), config).map_err(failed)?;
    let (inputs, devices) = Inputs::declare(&node, config).map_err(failed)?;
    add(spec, registry, devices);
    Ok(Some((node, inputs)))
}
