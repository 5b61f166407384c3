//! Tables on stdout, `TARGET` lines, and the same figures as JSON.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::measure::Summary;

/// One reported figure.
#[derive(Debug, Clone)]
pub struct Figure {
    pub bench: String,
    pub name: String,
    pub unit: &'static str,
    pub summary: Summary,
}

/// A figure with a target.
#[derive(Debug, Clone)]
pub struct Target {
    pub bench: String,
    pub name: String,
    pub unit: &'static str,
    pub value: f64,
    /// `"≤ 50 ns"`, `"≥ 1.8×"`.
    pub target: String,
    pub met: bool,
    pub note: String,
    /// Why the verdict can't be trusted (a busy machine), if it can't.
    pub inconclusive: Option<String>,
}

impl Target {
    /// `TARGET chain overhead per skill: 38 ns (target ≤ 50 ns): met`.
    pub fn line(&self) -> String {
        let met = match (&self.inconclusive, self.met) {
            (Some(_), true) => "met, INCONCLUSIVE",
            (Some(_), false) => "NOT met, INCONCLUSIVE",
            (None, true) => "met",
            (None, false) => "NOT met",
        };
        let mut note = if self.note.is_empty() { String::new() } else { format!(" — {}", self.note) };
        if let Some(why) = &self.inconclusive {
            note.push_str(&format!(" — INCONCLUSIVE: {why}"));
        }
        let sep = if self.unit == "×" { "" } else { " " };
        let value = fmt_value(self.value, self.unit);
        format!("TARGET {}: {value}{sep}{} (target {}): {met}{note}", self.name, self.unit, self.target)
    }
}

/// Everything one run reports.
#[derive(Debug, Default)]
pub struct Report {
    pub figures: Vec<Figure>,
    pub targets: Vec<Target>,
    pub notes: Vec<String>,
}

/// A number with as many decimals as its size deserves.
pub fn fmt_value(x: f64, unit: &str) -> String {
    let a = x.abs();
    if unit == "×" || a < 10.0 {
        format!("{x:.2}")
    } else if a < 100.0 {
        format!("{x:.1}")
    } else {
        format!("{x:.0}")
    }
}

/// The scale and unit a table shows: `ns` values from 10 µs on in µs.
fn scaled(x: f64, unit: &'static str) -> (f64, &'static str) {
    if unit == "ns" && x.abs() >= 10_000.0 {
        (1e-3, "µs")
    } else {
        (1.0, unit)
    }
}

impl Report {
    /// Records a figure and returns its median.
    pub fn figure(&mut self, bench: &str, name: &str, unit: &'static str, summary: &Summary) -> f64 {
        self.figures.push(Figure { bench: bench.into(), name: name.into(), unit, summary: summary.clone() });
        summary.median
    }

    /// Records a target line and prints it.
    pub fn target(&mut self, target: Target) {
        println!("{}", target.line());
        self.targets.push(target);
    }

    /// Prints the figures of `bench` as a table.
    pub fn print_table(&self, bench: &str, title: &str) {
        let rows: Vec<&Figure> = self.figures.iter().filter(|f| f.bench == bench).collect();
        let width = rows.iter().map(|f| f.name.chars().count()).max().unwrap_or(0).max(8);
        println!();
        println!("== {title}");
        println!("{:<width$}  {:>10}  {:>21}  {:>6}", "", "median", "q1 .. q3", "iqr");
        for f in rows {
            let s = &f.summary;
            let (k, unit) = scaled(s.median, f.unit);
            let m = s.median * k;
            let range = format!("{} .. {}", fmt_value(s.q1 * k, unit), fmt_value(s.q3 * k, unit));
            println!(
                "{:<width$}  {:>7} {:<2}  {:>21}  {:>5.1}%",
                f.name,
                fmt_value(m, unit),
                unit,
                range,
                s.spread_pct()
            );
        }
    }

    pub fn note(&mut self, text: impl Into<String>) {
        let text = text.into();
        println!("  note: {text}");
        self.notes.push(text);
    }

    /// The report as JSON (no dependency: the format is small and fixed).
    pub fn to_json(&self, machine: &Machine) -> String {
        let mut out = String::new();
        out.push_str("{\n");
        let _ = writeln!(out, "  \"date\": {},", json_str(&machine.date));
        let _ = writeln!(out, "  \"unix_time\": {},", machine.unix_time);
        let _ = writeln!(out, "  \"cpus\": {},", machine.cpus);
        let _ = writeln!(out, "  \"cpu_model\": {},", json_str(&machine.cpu_model));
        let _ = writeln!(out, "  \"args\": {},", json_str(&machine.args));
        let _ = writeln!(out, "  \"loadavg_at_start\": {},", json_str(&machine.loadavg));
        out.push_str("  \"targets\": [\n");
        for (i, t) in self.targets.iter().enumerate() {
            let _ = write!(
                out,
                "    {{\"bench\": {}, \"name\": {}, \"value\": {}, \"unit\": {}, \"target\": {}, \"met\": {}, \"inconclusive\": {}, \"line\": {}}}",
                json_str(&t.bench),
                json_str(&t.name),
                json_num(t.value),
                json_str(t.unit),
                json_str(&t.target),
                t.met,
                t.inconclusive.is_some(),
                json_str(&t.line())
            );
            out.push_str(if i + 1 < self.targets.len() { ",\n" } else { "\n" });
        }
        out.push_str("  ],\n  \"figures\": [\n");
        for (i, f) in self.figures.iter().enumerate() {
            let s = &f.summary;
            let _ = write!(
                out,
                "    {{\"bench\": {}, \"name\": {}, \"unit\": {}, \"median\": {}, \"q1\": {}, \"q3\": {}, \"samples\": {}}}",
                json_str(&f.bench),
                json_str(&f.name),
                json_str(f.unit),
                json_num(s.median),
                json_num(s.q1),
                json_num(s.q3),
                s.samples.len()
            );
            out.push_str(if i + 1 < self.figures.len() { ",\n" } else { "\n" });
        }
        out.push_str("  ],\n  \"notes\": [");
        for (i, n) in self.notes.iter().enumerate() {
            out.push_str(if i == 0 { "\n    " } else { ",\n    " });
            out.push_str(&json_str(n));
        }
        out.push_str(if self.notes.is_empty() { "]\n}\n" } else { "\n  ]\n}\n" });
        out
    }

    /// Writes the JSON report, creating the directory.
    pub fn write_json(&self, path: &Path, machine: &Machine) -> std::io::Result<()> {
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        std::fs::write(path, self.to_json(machine))
    }
}

fn json_num(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        "null".into()
    }
}

fn json_str(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// What the figures were measured on.
#[derive(Debug, Clone)]
pub struct Machine {
    pub date: String,
    pub unix_time: u64,
    pub cpus: usize,
    pub cpu_model: String,
    pub args: String,
    /// `/proc/loadavg` when the run started: other work on the machine.
    pub loadavg: String,
}

impl Machine {
    pub fn detect(args: &str) -> Machine {
        let unix_time =
            std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0);
        let cpu_model = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|s| {
                s.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split_once(':'))
                    .map(|(_, v)| v.trim().to_string())
            })
            .unwrap_or_else(|| "unknown".into());
        Machine {
            date: utc_date(unix_time),
            unix_time,
            cpus: std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
            cpu_model,
            args: args.into(),
            loadavg: loadavg(),
        }
    }
}

/// A snapshot of where the machine's CPU time went (Linux `/proc`), to tell
/// whether other work shared the cores during a benchmark.
#[derive(Debug, Clone, Copy, Default)]
pub struct CpuTimes {
    /// All CPUs: busy (user, nice, system, irq, softirq), idle (+ iowait),
    /// stolen by the hypervisor; in clock ticks.
    busy: u64,
    idle: u64,
    steal: u64,
    /// This process (user + system), in clock ticks.
    own: u64,
}

impl CpuTimes {
    pub fn now() -> Option<CpuTimes> {
        let stat = std::fs::read_to_string("/proc/stat").ok()?;
        let cpu: Vec<u64> = stat.lines().next()?.split_whitespace().skip(1).map(|x| x.parse().unwrap_or(0)).collect();
        let get = |i: usize| cpu.get(i).copied().unwrap_or(0);
        let own_stat = std::fs::read_to_string("/proc/self/stat").ok()?;
        // Fields after the `(comm)`, which may hold spaces: utime, stime are 14 and 15.
        let after = own_stat.rsplit_once(')')?.1;
        let f: Vec<u64> = after.split_whitespace().map(|x| x.parse().unwrap_or(0)).collect();
        let own = f.get(11).copied().unwrap_or(0) + f.get(12).copied().unwrap_or(0);
        Some(CpuTimes { busy: get(0) + get(1) + get(2) + get(5) + get(6), idle: get(3) + get(4), steal: get(7), own })
    }

    /// Where all CPUs' time went between `self` and `later`.
    pub fn since(&self, later: &CpuTimes) -> Option<CpuShare> {
        let busy = later.busy.saturating_sub(self.busy);
        let idle = later.idle.saturating_sub(self.idle);
        let steal = later.steal.saturating_sub(self.steal);
        let total = busy + idle + steal;
        if total == 0 {
            return None;
        }
        let own = later.own.saturating_sub(self.own).min(busy);
        let pct = |x: u64| x as f64 / total as f64 * 100.0;
        Some(CpuShare { own: pct(own), others: pct(busy - own), steal: pct(steal), idle: pct(idle) })
    }
}

/// Shares of all CPUs' time over an interval, in percent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CpuShare {
    /// This process.
    pub own: f64,
    /// Every other process.
    pub others: f64,
    /// Taken by the hypervisor.
    pub steal: f64,
    pub idle: f64,
}

impl CpuShare {
    /// Whether other processes or the hypervisor took enough CPU time to
    /// spoil a measurement that needs every core.
    pub fn busy(&self) -> bool {
        self.others + self.steal > 5.0
    }
}

impl std::fmt::Display for CpuShare {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "of all CPUs' time: this run {:.0}%, other processes {:.0}%, stolen by the hypervisor {:.0}%, idle {:.0}%",
            self.own, self.others, self.steal, self.idle
        )
    }
}

/// The 1, 5 and 15 minute load averages (empty where unknown).
pub fn loadavg() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_default()
}

/// `YYYY-MM-DD HH:MM UTC` of a Unix time (civil-from-days, H. Hinnant).
pub fn utc_date(unix: u64) -> String {
    let days = (unix / 86_400) as i64;
    let secs = unix % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02} {:02}:{:02} UTC", secs / 3600, secs % 3600 / 60)
}

/// Where results go: `$CARGO_TARGET_DIR/bench-results/core.json`, or the
/// target directory holding this executable (`<target>/release/deps/core-…`).
pub fn results_path(file: &str) -> PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).or_else(|| {
        let exe = std::env::current_exe().ok()?;
        let deps = exe.parent()?;
        let profile = deps.parent()?;
        Some(profile.parent()?.to_path_buf())
    });
    let target = target.unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../target")));
    target.join("bench-results").join(file)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_are_civil() {
        assert_eq!(utc_date(0), "1970-01-01 00:00 UTC");
        assert_eq!(utc_date(951_782_400), "2000-02-29 00:00 UTC");
        assert_eq!(utc_date(1_767_225_600 + 3_660), "2026-01-01 01:01 UTC");
    }

    #[test]
    fn json_escapes_and_lists_targets() {
        let mut r = Report::default();
        r.targets.push(Target {
            bench: "chain".into(),
            name: "chain \"overhead\"".into(),
            unit: "ns",
            value: 38.0,
            target: "≤ 50 ns".into(),
            met: true,
            note: String::new(),
            inconclusive: None,
        });
        let m = Machine {
            date: "d".into(),
            unix_time: 1,
            cpus: 2,
            cpu_model: "x".into(),
            args: String::new(),
            loadavg: String::new(),
        };
        let j = r.to_json(&m);
        assert!(j.contains("\"name\": \"chain \\\"overhead\\\"\""), "{j}");
        assert!(j.contains("\"line\": \"TARGET chain \\\"overhead\\\": 38.0 ns (target ≤ 50 ns): met\""), "{j}");
    }
}
