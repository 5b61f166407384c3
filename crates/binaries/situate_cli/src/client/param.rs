//! `situate param …`: one parameter's value (`get`, `set`), every value as one file (`dump`),
//! and such a file set (`load`, the file checked whole before anything is set).

use std::path::Path;

use serde_json::{json, Value as Json};

use super::command::ParamAction;
use super::connect::client_verb;
use crate::output::{problem, Exit, Out, Problem};

/// `situate param …`.
pub(super) fn param(action: ParamAction, out: Out) -> anyhow::Result<()> {
    match action {
        ParamAction::Get { skill, param, remote } => client_verb(&remote, |c, robot| {
            let v = c.request(robot, "get_param", &json!({"skill": skill, "param": param}))?;
            out.result(&v, || v.to_string());
            Ok(())
        }),
        ParamAction::Set { skill, param, value, remote } => client_verb(&remote, |c, robot| {
            // A number, true/false, or a JSON string; anything else is taken as text.
            let v: Json = serde_json::from_str(&value).unwrap_or_else(|_| Json::String(value.clone()));
            c.request(robot, "set_param", &json!({"skill": skill, "param": param, "value": v}))?;
            out.result(&json!({"skill": skill, "param": param, "value": v}), || {
                format!("{skill}.{param} = {v} (from the next cycle)")
            });
            Ok(())
        }),
        ParamAction::Dump { skill, remote } => client_verb(&remote, |c, robot| {
            let skills = c.request(robot, "skills", &json!({}))?;
            let mut dump = serde_json::Map::new();
            for s in skills.as_array().into_iter().flatten() {
                let name = s["name"].as_str().unwrap_or_default();
                if !skill.is_empty() && !skill.iter().any(|k| k == name) {
                    continue;
                }
                let params: serde_json::Map<String, Json> = s["params"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .map(|p| (p["name"].as_str().unwrap_or_default().to_string(), p["value"].clone()))
                    .collect();
                if !params.is_empty() {
                    dump.insert(name.to_string(), Json::Object(params));
                }
            }
            for k in &skill {
                if !dump.contains_key(k) && !skills.as_array().into_iter().flatten().any(|s| s["name"] == **k) {
                    return Err(problem(Exit::Refused, format!("no skill `{k}` on robot `{robot}`")));
                }
            }
            let dump = Json::Object(dump);
            // The text form is the file `param load` reads, pretty-printed.
            out.result(&dump, || serde_json::to_string_pretty(&dump).unwrap_or_default());
            Ok(())
        }),
        ParamAction::Load { file, remote } => {
            let values = read_param_file(&file)?;
            client_verb(&remote, |c, robot| {
                let mut set = Vec::new();
                for (skill, params) in &values {
                    for (param, value) in params {
                        c.request(robot, "set_param", &json!({"skill": skill, "param": param, "value": value}))?;
                        set.push(format!("{skill}.{param}"));
                    }
                }
                out.result(&json!({"set": set}), || format!("set {} parameters (from the next cycle)", set.len()));
                Ok(())
            })
        }
    }
}

/// One skill's parameter values, from a parameter file.
type SkillParams = (String, Vec<(String, Json)>);

/// A parameter file `{skill: {param: value}}`, checked whole before anything is set.
fn read_param_file(file: &Path) -> anyhow::Result<Vec<SkillParams>> {
    let shown = file.display();
    let text = std::fs::read_to_string(file)
        .map_err(|e| Problem::file_problem(format!("{shown}: cannot read the parameter file: {e}")))?;
    let root: Json =
        json5::from_str(&text).map_err(|e| Problem::file_problem(format!("{shown}: not JSON or JSON5: {e}")))?;
    let Json::Object(skills) = root else {
        return Err(Problem::file_problem(format!(
            "{shown}: expected an object {{skill: {{param: value}}}} (what `situate param dump` writes)"
        ))
        .into());
    };
    let mut out = Vec::new();
    for (skill, params) in skills {
        let Json::Object(params) = params else {
            return Err(Problem::file_problem(format!(
                "{shown}: `{skill}`: expected an object of parameter values {{param: value}}"
            ))
            .into());
        };
        out.push((skill, params.into_iter().collect()));
    }
    Ok(out)
}
