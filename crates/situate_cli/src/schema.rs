//! `situate schema`: JSON Schemas of the file formats.

use std::path::Path;

use serde_json::{json, Value as Json};

use crate::output::{problem, Exit, Out};

pub(crate) fn schema(format: &str) -> Option<Json> {
    match format {
        "robot" => Some(json!({})),
        _ => None,
    }
}

pub(crate) fn schema_command(format: &str, output: Option<&Path>, out: Out) -> anyhow::Result<()> {
    let schema = schema(format).ok_or_else(|| problem(Exit::Usage, format!("no schema `{format}`")))?;
    let text = serde_json::to_string_pretty(&schema)?;
    match output {
        Some(path) => {
            std::fs::write(path, text + "\n")
                .map_err(|e| problem(Exit::Failure, format!("writing {}: {e}", path.display())))?;
            out.note(format_args!("{}: the {format} schema written", path.display()));
        }
        None => println!("{text}"),
    }
    Ok(())
}
