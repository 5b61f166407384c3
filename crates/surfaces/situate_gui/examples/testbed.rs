//! A testbed for the GUI: the toy robot (`examples/toybot.yaml`), plus a tiny dskill `gui.circle`
//! writing a `truth.pose` that moves in a circle and printing now and then, served by the GUI
//! (with a fixture map for the world view) and by the sequencer link.
//!
//! ```text
//! cargo run -p situate_gui --example testbed -- [--gui-port N] [--link-port N] [--no-link]
//!     [--robot FILE] [--map FILE] [--sample-hz HZ] [--no-circle] [--rate-hz HZ]
//!     [--history-frames N] [--no-history] [--cars]
//! ```
//! `--cars` adds a `gui.cars` device writing `truth.cars` for the fixture map's one car (its floor
//! and door opening are parameters: a test moves the car and opens its door).
//! Prints `GUI http://…/`, `LINK tcp/…` and then `READY` when both serve; runs until killed or
//! until its standard input closes when `--stdin` is given.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{bail, Context as _};
use situate::manager::{Control, Manager, Request, RobotFile, RobotSpec, SkillSpec};
use situate::prelude::*;
use situate_gui::GuiConfig;
use situate_link::{Link, LinkConfig};
use situate_robot::{TruthCars, TruthPose};

/// Moves a ground-truth pose around a circle (for the world view) and prints every `print_every`
/// cycles (for verbose).
#[derive(Skill, Default)]
#[skill(name = "gui.circle", kind = "device")]
pub struct Circle {
    /// The pose on the circle, heading along it.
    #[output(signal = "truth.pose")]
    pose: TruthPose,
    /// Radius of the circle, metres.
    #[param(default = 2.0, min = 0.1, max = 10.0, unit = "m")]
    radius: f64,
    /// Period of one turn, seconds.
    #[param(default = 20.0, min = 1.0, max = 1000.0, unit = "s")]
    period_s: f64,
    /// Print a line every this many runs.
    #[param(default = 5, min = 1, max = 1000000)]
    print_every: i64,
    /// The floor the circle is on (a test moves the robot to another floor with it).
    #[param(default = 0, min = 0, max = 10)]
    floor: i64,
    runs: i64,
}

impl Body for Circle {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let a = std::f64::consts::TAU * cx.time_s() / self.period_s;
        self.pose = TruthPose {
            x: self.radius * a.cos(),
            y: self.radius * a.sin(),
            theta: a + std::f64::consts::FRAC_PI_2,
            floor: self.floor,
        };
        self.runs += 1;
        if self.runs % self.print_every == 0 {
            sprint!(cx, "circle run {} at ({:.2}, {:.2})", self.runs, self.pose.x, self.pose.y);
        }
        Ok(())
    }
}

/// The fixture map's one elevator car: its floor and door opening, as parameters.
#[derive(Skill, Default)]
#[skill(name = "gui.cars", kind = "device")]
pub struct Cars {
    /// The cars' floors and door openings.
    #[output(signal = "truth.cars")]
    cars: TruthCars,
    /// The car's floor (fractional while it moves).
    #[param(default = 0.0, min = -10.0, max = 10.0)]
    floor: f64,
    /// The car's door opening, 0 (closed) to 1 (open).
    #[param(default = 0.0, min = 0.0, max = 1.0)]
    door: f64,
}

impl Body for Cars {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        self.cars = TruthCars { floor: vec![self.floor].into(), door: vec![self.door].into() };
        Ok(())
    }
}

struct Options {
    gui_port: u16,
    link_port: Option<u16>,
    robot: PathBuf,
    map: Option<PathBuf>,
    sample_hz: f64,
    circle: bool,
    cars: bool,
    rate_hz: Option<f64>,
    stdin: bool,
    /// Frames the timeline keeps; `None`: no timeline.
    history_frames: Option<usize>,
}

fn parse() -> anyhow::Result<Options> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut o = Options {
        gui_port: 0,
        link_port: Some(7447),
        robot: root.join("../../../examples/toybot.yaml"),
        map: Some(root.join("examples/testbed_map.json")),
        sample_hz: 10.0,
        circle: true,
        cars: false,
        rate_hz: None,
        stdin: false,
        history_frames: Some(situate_gui::history::DEFAULT_FRAMES),
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().with_context(|| format!("{a} needs a value"));
        match a.as_str() {
            "--gui-port" => o.gui_port = value()?.parse().context("--gui-port")?,
            "--link-port" => o.link_port = Some(value()?.parse().context("--link-port")?),
            "--no-link" => o.link_port = None,
            "--robot" => o.robot = value()?.into(),
            "--map" => o.map = Some(value()?.into()),
            "--no-map" => o.map = None,
            "--sample-hz" => o.sample_hz = value()?.parse().context("--sample-hz")?,
            "--no-circle" => o.circle = false,
            "--cars" => o.cars = true,
            "--rate-hz" => o.rate_hz = Some(value()?.parse().context("--rate-hz")?),
            "--stdin" => o.stdin = true,
            "--history-frames" => o.history_frames = Some(value()?.parse().context("--history-frames")?),
            "--no-history" => o.history_frames = None,
            other => bail!("unknown option {other}"),
        }
    }
    Ok(o)
}

fn main() -> anyhow::Result<()> {
    let _ = tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn,zenoh=error".into()),
        )
        .with_writer(std::io::stderr)
        .try_init();
    let o = parse()?;
    let file = RobotFile::load(&o.robot)
        .map_err(|errors| anyhow::anyhow!(errors.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n")))?;
    let mut spec = RobotSpec::from_file(&file);
    if let Some(hz) = o.rate_hz {
        spec.period_s = 1.0 / hz;
    }
    let mut registry = situate_toys::registry();
    registry.register::<Circle>();
    registry.register::<Cars>();
    if o.circle {
        spec = spec.skill(SkillSpec::new("circle", "gui.circle"));
    }
    if o.cars {
        spec = spec.skill(SkillSpec::new("cars", "gui.cars"));
    }
    let world = match &o.map {
        None => None,
        Some(p) => {
            let text = std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?;
            Some(serde_json::from_str(&text).with_context(|| format!("{} is not JSON", p.display()))?)
        }
    };
    let mut manager = Manager::build(&spec, &registry).map_err(|e| anyhow::anyhow!("{e}"))?;
    // The timeline's tap, before the manager runs.
    let tap = o.history_frames.map(|_| situate_gui::HistoryTap::new(&mut manager));
    let (mut handle, join) = manager.spawn(true);
    let link = match o.link_port {
        None => None,
        Some(port) => {
            let config = LinkConfig { listen: vec![format!("tcp/127.0.0.1:{port}")], ..LinkConfig::default() };
            let session = Link::open(&config).context("opening the link")?;
            let served = Link::serve(&spec.robot, handle.clone(), session, &config).context("serving the link")?;
            println!("LINK tcp/127.0.0.1:{port}");
            Some(served)
        }
    };
    let gui = situate_gui::serve_with_history(
        handle.clone(),
        GuiConfig {
            listen: SocketAddr::from(([127, 0, 0, 1], o.gui_port)),
            world,
            sample_hz: o.sample_hz,
            history_frames: o.history_frames.unwrap_or(situate_gui::history::DEFAULT_FRAMES),
            ..GuiConfig::default()
        },
        tap,
    )?;
    println!("GUI {}", gui.url());
    if !situate_gui::has_web_app() {
        eprintln!("testbed: the web app was not built (run scripts/gui.sh build): serving the placeholder page");
    }
    println!("READY");
    if o.stdin {
        let mut sink = String::new();
        while std::io::stdin().read_line(&mut sink).map(|n| n > 0).unwrap_or(false) {
            sink.clear();
        }
    } else {
        loop {
            std::thread::sleep(Duration::from_secs(3600));
        }
    }
    gui.stop();
    drop(link);
    let _ = handle.request(Request::Shutdown);
    let _ = join.join();
    Ok(())
}
