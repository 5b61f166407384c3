//! Derived series: a formula of the condition language over the robot's
//! signal leaves (`abs(drive.w) * 2`, `odom.x * odom.x + odom.y * odom.y`,
//! `sonar.range[0] < 0.25`), plotted like a signal. Compiled once (when a tab
//! asks for it) against the robot's wiring, evaluated on the server: live at
//! each telemetry sample from the leaves' latest values, and over the
//! timeline from each cycle's values (`history_series`). Its value carries the
//! oldest cycle its leaves were written in, so it is a gap, as a signal is,
//! once one of them is no longer written.

use situate_core::{SignalType, Value};
use situate_expr::{Formula, Lookup, Resolver};
use situate_manager::graph::Graph;

/// The most formulas one tab plots.
pub const MAX_FORMULAS: usize = 8;
/// The longest formula accepted, in bytes.
pub const MAX_FORMULA_BYTES: usize = 500;

/// A compiled formula and the leaves it reads.
#[derive(Debug, Clone)]
pub struct Derived {
    formula: Formula,
}

/// Names resolve to the robot's signal leaves (ids: leaf indices in the
/// graph); a record resolves so that the language says it cannot be used
/// whole.
struct Leaves<'a>(&'a Graph);

impl Resolver for Leaves<'_> {
    fn resolve(&self, path: &str) -> Result<(usize, SignalType), String> {
        let g = self.0;
        if let Some(&l) = g.leaf_index.get(path) {
            return Ok((l, g.leaves[l].ty.clone()));
        }
        if let Some(ty) = g.records.get(path) {
            return Ok((usize::MAX, ty.clone()));
        }
        let names = g.leaves.iter().map(|l| l.path.as_str());
        Err(format!("unknown signal `{path}`{}", situate_core::suggestion(path, names)))
    }
}

/// The values of a formula's references, in the order of its refs.
struct Refs<'a> {
    ids: &'a [usize],
    values: &'a [Option<&'a Value>],
}

impl Lookup for Refs<'_> {
    fn value(&self, id: usize) -> Option<&Value> {
        let k = self.ids.iter().position(|&i| i == id)?;
        *self.values.get(k)?
    }
}

impl Derived {
    /// Compiles `source` against the robot's wiring; the error names the
    /// formula, the column and the problem.
    pub fn compile(source: &str, graph: &Graph) -> Result<Derived, String> {
        if source.len() > MAX_FORMULA_BYTES {
            return Err(format!("a formula of {} bytes: at most {MAX_FORMULA_BYTES}", source.len()));
        }
        // Sent under its own text beside the signals: a signal's name is the signal, not a formula.
        if graph.leaf_index.contains_key(source.trim()) || graph.records.contains_key(source.trim()) {
            return Err(format!("`{source}` is a signal: watch it as one (`signals`), not as a formula"));
        }
        Formula::compile(source, &Leaves(graph))
            .map(|formula| Derived { formula })
            .map_err(|e| format!("formula `{source}`: {e}"))
    }

    pub fn source(&self) -> &str {
        self.formula.source()
    }

    /// The leaf paths it reads, in the order [`Derived::eval`] takes them.
    pub fn leaves(&self) -> &[String] {
        self.formula.ref_names()
    }

    /// Its value from its leaves' (written cycle, value), in the order of
    /// [`Derived::leaves`]; with the oldest cycle among those that have one.
    /// `None`: it has no value (a leaf it needs has none, an index is out of
    /// range, the result is not a finite number), or none of its leaves has
    /// a value (`a || true` has a value though `a` has none, by the
    /// language's rules; with no leaf written at all it is not plotted).
    pub fn eval(&self, values: &[Option<(u64, &Value)>]) -> Option<(u64, f64)> {
        let refs: Vec<Option<&Value>> = values.iter().map(|v| v.map(|(_, v)| v)).collect();
        let v = self.formula.eval(&Refs { ids: self.formula.refs(), values: &refs })?;
        let oldest = values.iter().flatten().map(|(c, _)| *c).min()?;
        Some((oldest, v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use situate::manager::{Manager, RobotSpec, SkillSpec};

    #[test]
    fn a_formula_reads_leaves_by_path_and_says_what_is_wrong() {
        let spec = RobotSpec::new("f")
            .skill(SkillSpec::new("wheels", "toy.wheels"))
            .skill(SkillSpec::new("wander", "toy.wander"));
        let m = Manager::build(&spec, &situate_toys::registry()).unwrap_or_else(|e| panic!("{e}"));
        let g = m.graph();
        let d = Derived::compile("abs(odom.x) + drive.v * 2", g).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(d.leaves(), ["odom.x", "drive.v"]);
        let (x, v) = (Value::F64(-1.5), Value::F64(0.25));
        assert_eq!(d.eval(&[Some((7, &x)), Some((9, &v))]), Some((7, 2.0)));
        assert_eq!(d.eval(&[Some((7, &x)), None]), None, "a leaf without a value: no point");
        let e = Derived::compile("odom.z * 2", g).unwrap_err();
        assert!(e.starts_with("formula `odom.z * 2`: column 1: unknown signal `odom.z`"), "{e}");
        let e = Derived::compile("odom * 2", g).unwrap_err();
        assert!(e.contains("column 1") && e.contains("record"), "{e}");
        assert!(Derived::compile(&"1+".repeat(300), g).unwrap_err().contains("at most 500"));
        // A signal's own name is not a formula (it would stand in the signal's place in a sample).
        assert!(Derived::compile("odom.x", g).unwrap_err().contains("is a signal"));
    }
}
