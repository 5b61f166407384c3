//! Tasks beyond the one delivery: a list of *stops*, each a place where the robot must say its
//! message, and the judge that tells from the simulator's ground truth which stops were made.
//!
//! A stop is `office` (inside the map's office) or `lobby:F` (in front of floor F's call button,
//! within [`LOBBY_REACH_M`]). The task `office` is the paper's delivery. Stops are made in order:
//! an utterance counts for the first stop not yet made, if it is said at that stop's place.
//! The experiment (`scripts/experiment.py`) and `situate demo --task` use it.

use std::fmt;

use crate::geom::P2;
use crate::map::Map;

/// How near the call button (its barcode) the robot's centre must be for `lobby:F`, m.
pub const LOBBY_REACH_M: f64 = 2.0;

/// One place a message must be said at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stop {
    /// Inside the map's office.
    Office,
    /// In front of this floor's call button.
    Lobby(i64),
}

impl fmt::Display for Stop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Stop::Office => f.write_str("office"),
            Stop::Lobby(l) => write!(f, "lobby:{l}"),
        }
    }
}

/// A task that does not parse, or that the map cannot hold.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TaskError {
    #[error("task `{task}`: stop {index} `{stop}`: expected `office` or `lobby:FLOOR` (FLOOR an integer)")]
    Syntax { task: String, index: usize, stop: String },
    #[error("task `{task}`: no stops")]
    Empty { task: String },
    #[error("task `{task}`: stop {index} `{stop}`: {why}")]
    NotInMap { task: String, index: usize, stop: String, why: String },
}

/// Parses `office,lobby:3,…` (stops separated by commas, spaces allowed).
pub fn parse(task: &str) -> Result<Vec<Stop>, TaskError> {
    if task.trim().is_empty() {
        return Err(TaskError::Empty { task: task.to_string() });
    }
    let mut stops = Vec::new();
    for (i, s) in task.split(',').map(str::trim).enumerate() {
        let bad = || TaskError::Syntax { task: task.to_string(), index: i + 1, stop: s.to_string() };
        let stop = match s.split_once(':') {
            None if s == "office" => Stop::Office,
            Some(("lobby", f)) => Stop::Lobby(f.trim().parse().map_err(|_| bad())?),
            _ => return Err(bad()),
        };
        stops.push(stop);
    }
    Ok(stops)
}

/// Checks that `map` has every stop's place: an office, and a lobby on each floor named.
pub fn check(task: &str, stops: &[Stop], map: &Map) -> Result<(), TaskError> {
    for (i, s) in stops.iter().enumerate() {
        let why = match s {
            Stop::Office if map.office().is_none() => Some("the map has no office".to_string()),
            Stop::Lobby(l) => match map.floor(*l) {
                None => Some(format!("the map has no floor {l}")),
                Some(f) if f.lobby.is_none() => Some(format!("floor {l} has no lobby")),
                Some(_) => None,
            },
            Stop::Office => None,
        };
        if let Some(why) = why {
            return Err(TaskError::NotInMap { task: task.to_string(), index: i + 1, stop: s.to_string(), why });
        }
    }
    Ok(())
}

/// Something the robot said, where and when (ground truth).
#[derive(Debug, Clone, PartialEq)]
pub struct Utterance {
    /// Simulated time, s.
    pub time_s: f64,
    pub floor: i64,
    pub at: P2,
    pub text: String,
}

/// Whether `stop` is where `u` was said.
pub fn said_at(map: &Map, stop: Stop, u: &Utterance) -> bool {
    match stop {
        Stop::Office => map.in_office(u.floor, u.at),
        Stop::Lobby(l) => {
            u.floor == l
                && map
                    .floor(l)
                    .and_then(|f| f.lobby.as_ref())
                    .is_some_and(|lobby| lobby.button.dist(u.at) <= LOBBY_REACH_M)
        }
    }
}

/// When each stop was made (`None`: not made), taking the stops in order: each utterance
/// counts for the first stop not made yet, when said at its place.
pub fn judge(map: &Map, stops: &[Stop], said: &[Utterance]) -> Vec<Option<f64>> {
    let mut made = vec![None; stops.len()];
    let mut next = 0;
    for u in said {
        if next < stops.len() && said_at(map, stops[next], u) {
            made[next] = Some(u.time_s);
            next += 1;
        }
    }
    made
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_stops_and_names_the_bad_one() {
        assert_eq!(parse("office").unwrap(), vec![Stop::Office]);
        assert_eq!(parse("lobby:3, office").unwrap(), vec![Stop::Lobby(3), Stop::Office]);
        assert_eq!(parse("lobby:-1").unwrap(), vec![Stop::Lobby(-1)]);
        let e = parse("lobby:3,ofice").unwrap_err().to_string();
        assert!(e.contains("stop 2 `ofice`"), "{e}");
        assert!(parse("lobby:x").is_err());
        assert_eq!(parse(" "), Err(TaskError::Empty { task: " ".into() }));
        assert!(matches!(parse("office,"), Err(TaskError::Syntax { index: 2, .. })));
        for s in [Stop::Office, Stop::Lobby(-2)] {
            assert_eq!(parse(&s.to_string()).unwrap(), vec![s]);
        }
    }
}
