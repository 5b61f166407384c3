//! How files merge: what comes later wins (see the `include` module's
//! documentation for the rules by section).

use super::Entries;
use crate::yaml::{Node, Spanned};

/// `over` merged onto `base`: later wins (see the module's documentation).
pub(super) fn merge(mut base: Entries, over: Entries) -> Entries {
    for (key, value) in over {
        let Some(slot) = base.iter_mut().find(|(k, _)| k.value == key.value) else {
            base.push((key, value));
            continue;
        };
        let earlier = std::mem::replace(&mut slot.1, Spanned::new(Node::Null, value.pos));
        slot.1 = match (key.value.as_str(), earlier.value, value.value) {
            ("devices" | "skills", Node::Seq(items), Node::Seq(more)) => {
                Spanned::new(Node::Seq(merge_entries(items, more)), earlier.pos)
            }
            ("libraries" | "python", Node::Seq(mut items), Node::Seq(more)) => {
                items.extend(more);
                Spanned::new(Node::Seq(items), earlier.pos)
            }
            (_, _, later) => Spanned::new(later, value.pos),
        };
        slot.0 = key;
    }
    base
}

fn entry_name(item: &Spanned<Node>) -> Option<&str> {
    item.value.get("name").and_then(|n| n.value.as_text())
}

/// The entries of a section: `more`'s appended to `items`, except that one
/// named as an entry of `items` overrides it in place (each earlier entry
/// at most once, so a name twice in one file stays a duplicate).
fn merge_entries(mut items: Vec<Spanned<Node>>, more: Vec<Spanned<Node>>) -> Vec<Spanned<Node>> {
    let earlier = items.len();
    let mut overridden = vec![false; earlier];
    for item in more {
        let found = entry_name(&item)
            .and_then(|name| (0..earlier).find(|&i| !overridden[i] && entry_name(&items[i]) == Some(name)));
        match found {
            Some(i) => {
                overridden[i] = true;
                let base = std::mem::replace(&mut items[i], Spanned::new(Node::Null, item.pos));
                items[i] = merge_entry(base, item);
            }
            None => items.push(item),
        }
    }
    items
}

/// One entry overridden by a later one of the same name, key by key.
fn merge_entry(base: Spanned<Node>, over: Spanned<Node>) -> Spanned<Node> {
    let (mut entries, more) = match (base.value, over.value) {
        (Node::Map(entries), Node::Map(more)) => (entries, more),
        (_, later) => return Spanned::new(later, over.pos),
    };
    let gives = |key: &str| more.iter().any(|(k, _)| k.value == key);
    if gives("type") {
        entries.retain(|(k, _)| k.value != "remote");
    }
    if gives("remote") {
        entries.retain(|(k, _)| k.value != "type");
    }
    for (key, value) in more {
        if key.value == "name" {
            continue;
        }
        let Some(slot) = entries.iter_mut().find(|(k, _)| k.value == key.value) else {
            entries.push((key, value));
            continue;
        };
        let earlier = std::mem::replace(&mut slot.1, Spanned::new(Node::Null, value.pos));
        slot.1 = match (key.value.as_str(), earlier.value, value.value) {
            ("params" | "remap", Node::Map(mut names), Node::Map(later)) => {
                for (k, v) in later {
                    match names.iter_mut().find(|(n, _)| n.value == k.value) {
                        Some(slot) => *slot = (k, v),
                        None => names.push((k, v)),
                    }
                }
                Spanned::new(Node::Map(names), earlier.pos)
            }
            (_, _, later) => Spanned::new(later, value.pos),
        };
        slot.0 = key;
    }
    Spanned::new(Node::Map(entries), base.pos)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::yaml;

    fn map(source: &str) -> Entries {
        match yaml::parse(source).expect("YAML").value {
            Node::Map(entries) => entries,
            other => panic!("not a mapping: {other:?}"),
        }
    }

    #[test]
    fn later_sections_replace_and_entries_merge_by_name() {
        let base =
            map("cycle: {rate_hz: 10, clock: simulated}\nskills:\n  - {name: a, type: t.a, params: {x: 1, y: 2}}\n");
        let over = map("cycle: {rate_hz: 50}\nskills:\n  - {name: a, params: {y: 3}}\n  - {name: b, type: t.b}\n");
        let merged = merge(base, over);
        let root = Node::Map(merged);
        let cycle = root.get("cycle").expect("cycle");
        assert!(cycle.value.get("clock").is_none(), "replaced whole, not merged");
        let skills = root.get("skills").and_then(|s| s.value.as_seq()).expect("skills");
        assert_eq!(skills.len(), 2);
        let a = &skills[0].value;
        assert_eq!(a.get("type").and_then(|t| t.value.as_text()), Some("t.a"));
        let params = a.get("params").expect("params");
        assert_eq!(params.value.get("x").and_then(|v| v.value.as_i64()), Some(1));
        assert_eq!(params.value.get("y").and_then(|v| v.value.as_i64()), Some(3));
    }
}
