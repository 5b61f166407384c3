//! `GET /metrics`: the manager's health in Prometheus' text exposition format (version 0.0.4),
//! for a Prometheus server or any scraper.
//!
//! Each scrape asks the manager for its stats and its skills through the control API (between
//! cycles, never on the cycle's thread); the fault counts come from the `skill_faulted` events the
//! GUI server has seen since it started. Every series carries the robot's name as `robot`.
//!
//! | metric | type | what |
//! |---|---|---|
//! | `situate_cycles_total` | counter | cycles run |
//! | `situate_running` | gauge | 1 while the cycle runs |
//! | `situate_cycle_period_seconds` | gauge | the nominal period |
//! | `situate_cycle_rate_hz` | gauge | the achieved rate (0 when stopped) |
//! | `situate_cycle_last_seconds`, `_mean_seconds`, `_max_seconds` | gauge | cycle time |
//! | `situate_cycle_overruns_total` | counter | cycles longer than a period |
//! | `situate_cycle_late_starts_total` | counter | cycles started late, or periods skipped |
//! | `situate_cycle_lost_seconds_total` | counter | time lost to skipped periods |
//! | `situate_request_hold_seconds_total` | counter | how long requests held the cycle back |
//! | `situate_worker_failures_total` | counter | worker threads that panicked |
//! | `situate_skill_active{skill}` | gauge | 1 if active |
//! | `situate_skill_faulted{skill}` | gauge | 1 if its last run faulted it (until reactivated) |
//! | `situate_skill_faults_total{skill}` | counter | `skill_faulted` events seen by this server |
//! | `situate_skill_runs_total{skill}` | counter | runs of its body |
//! | `situate_skill_seconds_total{skill}` | counter | time in its body |
//! | `situate_skill_last_seconds{skill}`, `situate_skill_max_seconds{skill}` | gauge | its body's last and longest run |

use std::collections::HashMap;
use std::fmt::Write;

use situate_manager::{ManagerStats, SkillInfo};

/// The content type of the text format.
pub const CONTENT_TYPE: &str = "text/plain; version=0.0.4; charset=utf-8";

/// Escapes a label value: backslash, double quote and newline.
fn label(value: &str) -> String {
    value.replace('\\', "\\\\").replace('"', "\\\"").replace('\n', "\\n")
}

/// A sample value as the format writes it (`+Inf`, `-Inf`, `NaN` for the non-finite).
fn number(v: f64) -> String {
    if v.is_nan() {
        "NaN".into()
    } else if v.is_infinite() {
        if v > 0.0 { "+Inf" } else { "-Inf" }.into()
    } else {
        format!("{v}")
    }
}

struct Out {
    text: String,
    robot: String,
}

impl Out {
    fn family(&mut self, name: &str, kind: &str, help: &str) {
        let _ = writeln!(self.text, "# HELP {name} {help}\n# TYPE {name} {kind}");
    }

    fn sample(&mut self, name: &str, skill: Option<&str>, value: f64) {
        let skill = skill.map(|s| format!(",skill=\"{}\"", label(s))).unwrap_or_default();
        let _ = writeln!(self.text, "{name}{{robot=\"{}\"{skill}}} {}", self.robot, number(value));
    }

    fn one(&mut self, name: &str, kind: &str, help: &str, value: f64) {
        self.family(name, kind, help);
        self.sample(name, None, value);
    }
}

/// Renders one scrape: the manager's stats, its skills, and the faults seen per skill.
pub fn render(stats: &ManagerStats, skills: &[SkillInfo], faults: &HashMap<String, u64>) -> String {
    let mut o = Out { text: String::new(), robot: label(&stats.robot) };
    let ns = 1e-9;
    o.one("situate_cycles_total", "counter", "Cycles run.", stats.cycle as f64);
    o.one("situate_running", "gauge", "1 while the cycle runs.", if stats.running { 1.0 } else { 0.0 });
    o.one("situate_cycle_period_seconds", "gauge", "The nominal cycle period.", stats.period_s);
    o.one("situate_cycle_rate_hz", "gauge", "The achieved cycle rate (0 when stopped).", stats.rate_hz);
    o.one("situate_cycle_last_seconds", "gauge", "The last cycle's time.", stats.last_cycle_ns as f64 * ns);
    o.one("situate_cycle_mean_seconds", "gauge", "The mean cycle time.", stats.mean_cycle_ns * ns);
    o.one("situate_cycle_max_seconds", "gauge", "The longest cycle time.", stats.max_cycle_ns as f64 * ns);
    o.one("situate_cycle_overruns_total", "counter", "Cycles that took longer than a period.", stats.overruns as f64);
    o.one(
        "situate_cycle_late_starts_total",
        "counter",
        "Cycles that started late, and periods skipped.",
        stats.late_starts as f64,
    );
    o.one(
        "situate_cycle_lost_seconds_total",
        "counter",
        "Time lost to cycles that started so late that periods were skipped.",
        stats.lost_ns as f64 * ns,
    );
    o.one(
        "situate_request_hold_seconds_total",
        "counter",
        "How long requests served between cycles held the next cycle back.",
        stats.request_hold_ns as f64 * ns,
    );
    o.one("situate_worker_failures_total", "counter", "Worker threads that panicked.", stats.worker_failures as f64);
    type Per = fn(&SkillInfo, &HashMap<String, u64>) -> f64;
    let families: [(&str, &str, &str, Per); 7] = [
        ("situate_skill_active", "gauge", "1 if the skill is active.", |s, _| f64::from(u8::from(s.active))),
        ("situate_skill_faulted", "gauge", "1 if the skill is faulted (until it is activated again).", |s, _| {
            f64::from(u8::from(s.faulted.is_some()))
        }),
        ("situate_skill_faults_total", "counter", "Faults of the skill seen by this server.", |s, f| {
            f.get(&s.name).copied().unwrap_or(0) as f64
        }),
        ("situate_skill_runs_total", "counter", "Runs of the skill's body.", |s, _| s.timing.runs as f64),
        ("situate_skill_seconds_total", "counter", "Time spent in the skill's body.", |s, _| {
            s.timing.total_ns as f64 * 1e-9
        }),
        ("situate_skill_last_seconds", "gauge", "The skill body's last run time.", |s, _| {
            s.timing.last_ns as f64 * 1e-9
        }),
        ("situate_skill_max_seconds", "gauge", "The skill body's longest run time.", |s, _| {
            s.timing.max_ns as f64 * 1e-9
        }),
    ];
    for (name, kind, help, per) in families {
        o.family(name, kind, help);
        for s in skills {
            o.sample(name, Some(&s.name), per(s, faults));
        }
    }
    o.text
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Checks every line against the text format's grammar (comments, then `name{labels} value`)
    /// and returns the samples.
    pub(crate) fn parse(text: &str) -> HashMap<String, f64> {
        let mut samples = HashMap::new();
        let mut typed = std::collections::HashSet::new();
        for line in text.lines() {
            if let Some(rest) = line.strip_prefix("# TYPE ") {
                let mut it = rest.split(' ');
                let (name, kind) = (it.next().unwrap_or(""), it.next().unwrap_or(""));
                assert!(["counter", "gauge"].contains(&kind), "{line}");
                assert!(typed.insert(name.to_string()), "a family declared twice: {line}");
                continue;
            }
            if line.starts_with("# HELP ") {
                continue;
            }
            let (series, value) = line.rsplit_once(' ').unwrap_or_else(|| panic!("no value: {line}"));
            let name = series.split('{').next().unwrap_or("");
            assert!(typed.contains(name), "a sample before its TYPE: {line}");
            assert!(
                name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                    && !name.starts_with(|c: char| c.is_ascii_digit()),
                "{line}"
            );
            assert!(series.ends_with('}') && series.contains("{robot=\""), "{line}");
            let v: f64 = match value {
                "+Inf" => f64::INFINITY,
                "-Inf" => f64::NEG_INFINITY,
                "NaN" => f64::NAN,
                v => v.parse().unwrap_or_else(|_| panic!("not a number: {line}")),
            };
            assert!(samples.insert(series.to_string(), v).is_none(), "a series twice: {line}");
        }
        assert!(text.ends_with('\n'));
        samples
    }

    #[test]
    fn label_values_are_escaped_and_numbers_follow_the_format() {
        assert_eq!(label("a\"b\\c\nd"), "a\\\"b\\\\c\\nd");
        assert_eq!(number(f64::INFINITY), "+Inf");
        assert_eq!(number(f64::NAN), "NaN");
        assert_eq!(number(0.25), "0.25");
        let stats = ManagerStats {
            robot: "r\"1".into(),
            cycle: 42,
            time_s: 1.0,
            running: true,
            period_s: 0.02,
            last_cycle_ns: 1_500_000,
            mean_cycle_ns: 1e6,
            max_cycle_ns: 3_000_000,
            overruns: 2,
            late_starts: 1,
            request_hold_ns: 0,
            lost_ns: 0,
            worker_failures: 0,
            rate_hz: 49.5,
            active: vec![],
        };
        let samples = parse(&render(&stats, &[], &HashMap::new()));
        assert_eq!(samples["situate_cycles_total{robot=\"r\\\"1\"}"], 42.0);
        assert_eq!(samples["situate_cycle_max_seconds{robot=\"r\\\"1\"}"], 0.003);
        assert_eq!(samples["situate_cycle_overruns_total{robot=\"r\\\"1\"}"], 2.0);
    }
}
