//! `situate run`: a robot file started, run until its cycles are done or it is told to stop,
//! then its summary (as text, or the protocol's `stats` and `skills` under `--json`).

use std::time::{Duration, Instant};

use serde_json::{json, Value as Json};
use situate::manager::{Event, ManagerStats, SkillInfo};

use super::recording::{recording_json, recording_text};
use super::start::{start_robot, RunOptions};
use crate::args::RunArgs;
use crate::output::{problem, Exit, Out, Problem};
use crate::signals;
use crate::sim::SimOverrides;
use crate::Extensions;

/// `situate run`.
pub(crate) fn run_robot(args: RunArgs, ext: &Extensions, out: Out) -> anyhow::Result<()> {
    let RunArgs {
        file,
        cycles,
        executor,
        clock,
        no_link,
        listen,
        map,
        seed,
        world,
        speed,
        stopped,
        gui,
        no_gui,
        gui_allow_host,
        record,
        record_dir,
        compose,
    } = args;
    let opts = RunOptions {
        cycles,
        executor,
        clock,
        no_link,
        listen,
        listen_fallback: false,
        sim: SimOverrides { map, seed, world },
        speed,
        stopped,
        gui,
        no_gui,
        gui_allow_hosts: gui_allow_host,
        compose,
        record,
        record_dir,
    };
    // Before starting: a signal during the start stops the robot once started.
    let interrupted = signals::Stop::install()?;
    let running = start_robot(&file, &opts, ext, out)?;
    let started = Instant::now();
    loop {
        if let Some(sig) = interrupted.signal() {
            out.note(format_args!("{}: stopping (again to exit at once)", signals::name(sig)));
            break;
        }
        match running.events.recv_timeout(Duration::from_millis(100)) {
            Ok(Event::SkillFaulted { skill, cause, cycle }) if !out.quiet => {
                eprintln!("cycle {cycle}: skill `{skill}` faulted: {cause}")
            }
            Ok(Event::ManagerStopped { cycle }) if cycles.is_some_and(|n| cycle >= n) => break,
            _ => {}
        }
        if cycles.is_some() && started.elapsed() > Duration::from_secs(1) {
            // A stop requested over the link also ends a bounded run. Bounded:
            // a stuck cycle must not keep this loop from seeing a signal.
            let asked =
                running.handle.request_timeout(situate::manager::Request::QueryStats, Duration::from_millis(200));
            if let Ok(situate::manager::Reply::Stats(s)) = asked {
                if cycles.is_some_and(|n| s.cycle >= n) && !s.running {
                    break;
                }
            }
        }
    }
    match running.finish() {
        Ok((stats, skills, recorded)) => {
            let recording = match recorded.transpose() {
                Ok(summary) => summary,
                Err(e) => return Err(problem(Exit::Failure, format!("--record: {e}"))),
            };
            let mut json = summary_json(&stats, &skills);
            if let Some(r) = &recording {
                json["recording"] = recording_json(r);
            }
            out.result(&json, || {
                let mut text = summary_text(&stats, &skills);
                if let Some(r) = &recording {
                    if !text.is_empty() && !text.ends_with('\n') {
                        text.push('\n');
                    }
                    text.push_str(recording_text(r).trim_end());
                }
                text
            });
            Ok(())
        }
        Err(stuck) => Err(Problem {
            lines: vec![format!("situate: {stuck}")],
            ..Problem::new(Exit::Failure, "no summary: the manager did not answer").said_by_situate()
        }
        .into()),
    }
}

/// The summary under `--json`: the protocol's `stats` and `skills` replies (docs/protocol.md).
fn summary_json(stats: &ManagerStats, skills: &[SkillInfo]) -> Json {
    json!({
        "stats": situate_link::json::stats_to_json(stats),
        "skills": skills.iter().map(situate_link::json::skill_to_json).collect::<Vec<_>>(),
    })
}

fn summary_text(stats: &ManagerStats, skills: &[SkillInfo]) -> String {
    use std::fmt::Write as _;
    let mut text = String::new();
    let _ = writeln!(text, "robot `{}`: {} cycles, {:.3} s on its clock", stats.robot, stats.cycle, stats.time_s);
    let _ = writeln!(
        text,
        "cycle time: mean {:.1} µs, max {:.1} µs; period {:.1} ms; overruns {}; late starts {}",
        stats.mean_cycle_ns / 1e3,
        stats.max_cycle_ns as f64 / 1e3,
        stats.period_s * 1e3,
        stats.overruns,
        stats.late_starts
    );
    let _ = writeln!(
        text,
        "{:<16} {:<8} {:>8} {:>10} {:>10} {:>10}  state",
        "skill", "kind", "runs", "mean µs", "max µs", "total ms"
    );
    for s in skills {
        let state = match (&s.faulted, s.active) {
            (Some(cause), _) => format!("faulted: {cause}"),
            (None, true) => "active".to_string(),
            (None, false) => "inactive".to_string(),
        };
        let _ = writeln!(
            text,
            "{:<16} {:<8} {:>8} {:>10.2} {:>10.2} {:>10.3}  {state}",
            s.name,
            s.kind.name(),
            s.timing.runs,
            s.timing.mean_ns() / 1e3,
            s.timing.max_ns as f64 / 1e3,
            s.timing.total_ns as f64 / 1e6
        );
    }
    text.trim_end().to_string()
}
