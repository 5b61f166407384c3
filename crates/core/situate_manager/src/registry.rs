//! The registry of skill types a robot file can name.

use std::collections::BTreeMap;

use situate_core::{suggestion, Declare, SkillType};

/// Skill types by name. The `situate` program registers the standard
/// libraries; embedders register their own.
#[derive(Default, Clone, Debug)]
pub struct Registry {
    types: BTreeMap<String, SkillType>,
}

impl Registry {
    pub fn new() -> Self {
        Registry::default()
    }

    /// Registers a Rust skill type under its declared name.
    pub fn register<T: Declare>(&mut self) -> &mut Self {
        self.add(SkillType::of::<T>())
    }

    /// Registers any skill type (foreign bindings, tests). A later type of
    /// the same name replaces the earlier one.
    pub fn add(&mut self, skill_type: SkillType) -> &mut Self {
        self.types.insert(skill_type.decl.type_name.clone(), skill_type);
        self
    }

    pub fn get(&self, type_name: &str) -> Option<&SkillType> {
        self.types.get(type_name)
    }

    /// `unknown skill type `x` — did you mean `y`?`
    pub fn unknown(&self, type_name: &str) -> String {
        format!("unknown skill type `{type_name}`{}", suggestion(type_name, self.types.keys().map(String::as_str)))
    }

    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.types.keys().map(String::as_str)
    }
}
