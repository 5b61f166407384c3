//! What a history's frames are named by: the robot's leaves and its skills as wired (their
//! ports, activation and parameters as built).

use situate_core::Value;
#[cfg(doc)]
use situate_manager::Frame;
use situate_manager::Graph;

/// One port of a skill: the leaves that make its value.
#[derive(Debug, Clone, PartialEq)]
pub struct PortLayout {
    pub name: String,
    pub signal: String,
    /// Leaf indices (into [`Layout::leaves`]).
    pub leaves: Vec<usize>,
}

/// One skill instance as wired, and its state when the history began.
#[derive(Debug, Clone, PartialEq)]
pub struct SkillLayout {
    pub name: String,
    pub active: bool,
    /// (name, value) of every parameter, in declaration order.
    pub params: Vec<(String, Value)>,
    pub inputs: Vec<PortLayout>,
    pub outputs: Vec<PortLayout>,
}

/// One leaf signal: its path and its writers (instance indices).
#[derive(Debug, Clone, PartialEq)]
pub struct LeafLayout {
    pub path: String,
    pub writers: Vec<usize>,
}

/// What a history needs to name what its frames hold: the leaves and the skills, by index as in
/// [`Frame`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Layout {
    pub leaves: Vec<LeafLayout>,
    pub skills: Vec<SkillLayout>,
}

impl Layout {
    /// The layout of a wired robot, with its skills' activation and parameters as built.
    pub fn of(graph: &Graph) -> Layout {
        let port = |p: &situate_manager::graph::PortBinding| PortLayout {
            name: p.name.clone(),
            signal: p.signal.clone(),
            leaves: p.leaves.clone(),
        };
        Layout {
            leaves: graph
                .leaves
                .iter()
                .map(|l| LeafLayout { path: l.path.clone(), writers: l.writers.iter().map(|(i, _)| *i).collect() })
                .collect(),
            skills: graph
                .instances
                .iter()
                .map(|d| SkillLayout {
                    name: d.name.clone(),
                    active: d.active,
                    params: d
                        .skill_type
                        .decl
                        .params
                        .iter()
                        .map(|p| p.name.clone())
                        .zip(d.params.iter().cloned())
                        .collect(),
                    inputs: d.inputs.iter().map(port).collect(),
                    outputs: d.outputs.iter().map(port).collect(),
                })
                .collect(),
        }
    }
}
