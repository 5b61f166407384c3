//! `situate map`: generating a building and checking one (docs/maps.md),
//! and telling a map file from a robot file for `situate check`.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use clap::Subcommand;
use serde_json::{json, Value as Json};
use situate_sim::generate;

use crate::output::{problem, Exit, Out};

#[derive(Subcommand)]
pub(crate) enum MapCommand {
    /// Generate a delivery building from a seed (the family and options: docs/maps.md). The same
    /// seed and options give the same file, byte for byte. Each option is a range `MIN..MAX` (or
    /// one value) the seed draws from.
    Generate {
        /// The seed.
        #[arg(long)]
        seed: u64,
        /// Floors in all, start and goal included (2..6).
        #[arg(long, value_parser = generate::parse_int_range, default_value = "2..6")]
        floors: (i64, i64),
        /// Elevator cars (1..4).
        #[arg(long, value_parser = generate::parse_int_range, default_value = "1..4")]
        cars: (i64, i64),
        /// Corridor width, m (within 1.8..3.0).
        #[arg(long, value_parser = generate::parse_range, default_value = "1.8..2.6")]
        corridor_width: (f64, f64),
        /// Door width (lab, rooms, office, cars), m (within 0.8..1.6).
        #[arg(long, value_parser = generate::parse_range, default_value = "1.0..1.4")]
        door_width: (f64, f64),
        /// Junctions on the start floor's way to the lobby (1..3).
        #[arg(long, value_parser = generate::parse_int_range, default_value = "1..3")]
        junctions: (i64, i64),
        /// Clutter boxes per metre of corridor wall, 0..1 (default: drawn in 0..0.3).
        #[arg(long)]
        clutter: Option<f64>,
        /// The elevator's open_s, s (default: drawn from [8, 12] to [15, 25]).
        #[arg(long, value_parser = generate::parse_range)]
        open_s: Option<(f64, f64)>,
        /// A door barcode's distance from the nearer jamb, m (within 0.1..0.6, the rule maps are held to).
        #[arg(long, value_parser = generate::parse_range, default_value = "0.1..0.6")]
        barcode_offset: (f64, f64),
        /// No route hints in the mission.
        #[arg(long)]
        no_route: bool,
        /// The family of buildings: 2 draws from the whole space docs/maps.md allows; 1 is the
        /// family before issue 37, frozen (a seed gives the building it gave then).
        #[arg(long, default_value_t = 2)]
        family: u32,
        /// The map file to write (`-`: standard output).
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Check a map: the loader's errors, then the mission's feasibility for the delivery robot
    /// (reachability, barcodes readable, cars boardable, doors, route). Every finding is reported
    /// as FILE:LINE: ELEMENT: MESSAGE; exit status 1 when there is any.
    Check { file: PathBuf },
    /// Print the whole building as JSON (floors, walls, doors, barcodes, elevator, mission), for
    /// another simulator or a tool built from the same map (its shape: docs/maps.md).
    Show { file: PathBuf },
}

pub(crate) fn map_command(command: MapCommand, out: Out) -> anyhow::Result<u8> {
    match command {
        MapCommand::Generate {
            seed,
            floors,
            cars,
            corridor_width,
            door_width,
            junctions,
            clutter,
            open_s,
            barcode_offset,
            no_route,
            family,
            output,
        } => {
            let opts = generate::Options {
                floors,
                cars,
                corridor_width,
                door_width,
                junctions,
                clutter,
                open_s,
                barcode_offset,
                route: !no_route,
                family,
            };
            let g = generate::generate(seed, &opts).map_err(|e| problem(Exit::Usage, e.to_string()))?;
            if output.as_os_str() == "-" {
                stdout!("{}", g.yaml);
            } else {
                std::fs::write(&output, &g.yaml).with_context(|| format!("cannot write {}", output.display()))?;
                if out.json {
                    let file = output.display().to_string();
                    stdoutln!("{}", json!({"file": file, "seed": seed, "features": g.features.to_json()}));
                } else {
                    eprintln!("{}: building of seed {seed} written", output.display());
                }
            }
            Ok(Exit::Ok.code())
        }
        MapCommand::Check { file } => map_check(&file, out.json),
        MapCommand::Show { file } => {
            let map = situate_sim::load_map(&file).map_err(|e| problem(Exit::BadFile, e.to_string()))?;
            stdoutln!("{}", map.building_json());
            Ok(Exit::Ok.code())
        }
    }
}

fn map_check(file: &Path, json: bool) -> anyhow::Result<u8> {
    let shown = file.display().to_string();
    // A map that cannot be read is one finding, about the map as a whole unless its reader
    // named the element; a map that reads is checked against every documented rule.
    let findings: Vec<situate_sim::Diagnostic> = match situate_sim::load_map(file) {
        Err(e) => vec![e],
        Ok(map) => situate_sim::check::lint(&map).into_iter().map(|f| f.in_file(&shown)).collect(),
    };
    let findings: Vec<Json> = findings
        .iter()
        .map(|f| {
            json!({
                "line": f.line(),
                "element": f.element.as_deref().unwrap_or("map"),
                "message": f.message,
                "text": f.to_string(),
            })
        })
        .collect();
    if json {
        stdoutln!("{}", json!({"file": shown, "ok": findings.is_empty(), "findings": findings}));
    } else if findings.is_empty() {
        stdoutln!("{shown}: ok");
    } else {
        for f in &findings {
            eprintln!("{}", f["text"].as_str().unwrap_or_default());
        }
        eprintln!("{shown}: {} finding{}", findings.len(), if findings.len() == 1 { "" } else { "s" });
    }
    Ok(if findings.is_empty() { Exit::Ok.code() } else { Exit::Failure.code() })
}

/// Whether the text looks like a map file (top-level `floors:` or `elevator:`)
/// rather than a robot file. Reads no more than a robot file may hold (a
/// device such as /dev/zero never ends: the robot-file reader reports it).
pub(crate) fn looks_like_map(file: &Path) -> bool {
    use std::io::Read as _;
    let Ok(f) = std::fs::File::open(file) else { return false };
    let mut bytes = Vec::new();
    if f.take(1 << 20).read_to_end(&mut bytes).is_err() {
        return false;
    }
    let text = String::from_utf8_lossy(&bytes);
    let top = |key: &str| text.lines().any(|l| l.starts_with(key));
    !top("robot:") && (top("floors:") || top("elevator:"))
}
