//! The registry of skill types a robot file can name.

use std::collections::BTreeMap;

use situate_core::{suggestion, Declare, Resources, SkillType};

/// Skill types by name, and the resources their instances are made with. The
/// `situate` program registers the standard libraries (and provides the
/// simulator's `world` to its devices); embedders register their own.
#[derive(Default, Clone, Debug)]
pub struct Registry {
    types: BTreeMap<String, SkillType>,
    resources: Resources,
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

    /// Provides `value` as the resource `name` to every skill made from this
    /// registry (a later one of the same name replaces it). A skill asks for
    /// it when it is made (`#[resource]`; docs/skills.md, "Resources").
    pub fn provide<T: std::any::Any + Send + Sync>(&mut self, name: impl Into<String>, value: T) -> &mut Self {
        self.resources.insert(name, value);
        self
    }

    /// Provides every resource of `resources` (another registry's, say) too.
    pub fn provide_all(&mut self, resources: &Resources) -> &mut Self {
        self.resources.extend_from(resources);
        self
    }

    /// The resources provided so far.
    pub fn resources(&self) -> &Resources {
        &self.resources
    }
}
