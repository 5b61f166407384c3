//! What a host program hands to the skills it builds: a device's handle, the simulator's world,
//! a model loaded once. A skill gets its resources when it is made, never later, so a body
//! always has what it needs and a missing one is a build error naming the skill, not a fault in
//! the middle of a run.
//!
//! Resources are named, so that every language can ask for one: a Rust skill by a field marked
//! `#[resource]` (the field's name, or `#[resource(name = "…")]`), a Python class skill by its
//! `__init__`'s parameter names, a C or C++ skill by `situate_resources.get`. In Rust the name's
//! value must also be of the field's type.

use std::any::Any;
use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

/// Named values a host provides to the skills it builds (see the module docs).
///
/// Cheap to clone: the values are shared, never copied.
#[derive(Clone, Default)]
pub struct Resources {
    entries: BTreeMap<String, Entry>,
}

#[derive(Clone)]
struct Entry {
    value: Arc<dyn Any + Send + Sync>,
    type_name: &'static str,
}

/// A resource a skill asked for that the host did not provide as asked.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ResourceError {
    /// No resource of that name.
    #[error("needs the resource `{name}` (a `{wanted}`), and the program provides none of that name ({})", provided_text(.provided))]
    Missing {
        name: String,
        wanted: &'static str,
        /// The names the host provides.
        provided: Vec<String>,
    },
    /// A resource of that name, of another type.
    #[error("needs the resource `{name}` as a `{wanted}`, and the program provides a `{is}`")]
    WrongType { name: String, wanted: &'static str, is: &'static str },
}

fn provided_text(provided: &[String]) -> String {
    if provided.is_empty() {
        "it provides no resources".to_string()
    } else {
        let names: Vec<String> = provided.iter().map(|n| format!("`{n}`")).collect();
        format!("it provides {}", names.join(", "))
    }
}

impl Resources {
    pub fn new() -> Self {
        Resources::default()
    }

    /// Provides `value` as `name` (replacing a resource of that name).
    pub fn insert<T: Any + Send + Sync>(&mut self, name: impl Into<String>, value: T) -> &mut Self {
        let entry = Entry { value: Arc::new(value), type_name: std::any::type_name::<T>() };
        self.entries.insert(name.into(), entry);
        self
    }

    /// Provides every resource of `other` too (one of a name provided here already is replaced).
    pub fn extend_from(&mut self, other: &Resources) -> &mut Self {
        for (name, entry) in &other.entries {
            self.entries.insert(name.clone(), entry.clone());
        }
        self
    }

    /// The resource `name`, if it is a `T`.
    pub fn get<T: Any>(&self, name: &str) -> Result<&T, ResourceError> {
        let wanted = std::any::type_name::<T>();
        let entry = self.entries.get(name).ok_or_else(|| ResourceError::Missing {
            name: name.to_string(),
            wanted,
            provided: self.entries.keys().cloned().collect(),
        })?;
        entry.value.downcast_ref::<T>().ok_or(ResourceError::WrongType {
            name: name.to_string(),
            wanted,
            is: entry.type_name,
        })
    }

    /// The resource `name` as whatever it is (the language bindings read their own types).
    pub fn get_any(&self, name: &str) -> Option<&(dyn Any + Send + Sync)> {
        self.entries.get(name).map(|e| &*e.value)
    }

    /// The names provided, in order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.entries.keys().map(String::as_str)
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

impl fmt::Debug for Resources {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_map().entries(self.entries.iter().map(|(n, e)| (n, e.type_name))).finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_resource_is_found_by_name_and_type() {
        let mut r = Resources::new();
        r.insert("port", 7_u16).insert("name", String::from("left"));
        assert_eq!(r.get::<u16>("port"), Ok(&7));
        assert_eq!(r.get::<String>("name").map(String::as_str), Ok("left"));
        assert_eq!(r.names().collect::<Vec<_>>(), ["name", "port"]);
    }

    #[test]
    fn a_missing_resource_says_what_is_provided() {
        let mut r = Resources::new();
        let e = r.get::<u16>("port").unwrap_err();
        assert_eq!(e.to_string(), "needs the resource `port` (a `u16`), and the program provides none of that name (it provides no resources)");
        r.insert("bus", 1_u8).insert("world", 2_u8);
        let e = r.get::<u16>("port").unwrap_err();
        assert!(e.to_string().ends_with("(it provides `bus`, `world`)"), "{e}");
    }

    #[test]
    fn a_resource_of_another_type_names_both() {
        let mut r = Resources::new();
        r.insert("port", 7_u32);
        let e = r.get::<u16>("port").unwrap_err();
        assert_eq!(e.to_string(), "needs the resource `port` as a `u16`, and the program provides a `u32`");
    }
}
