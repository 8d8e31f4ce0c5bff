//! Keys given twice in one object of a spec: serde_json keeps the last of them
//! silently, but a spec with two `problem`s is a mistake to name, not to guess.

use super::path::{render, steps, Step};
use super::SpecError;

/// A JSON document whose objects have no key twice (serde_json keeps the last of
/// them silently; a spec with two `problem`s is a mistake to name, not to guess).
struct UniqueKeys;

impl<'de> serde::Deserialize<'de> for UniqueKeys {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = UniqueKeys;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a JSON value")
            }
            fn visit_bool<E>(self, _: bool) -> Result<UniqueKeys, E> {
                Ok(UniqueKeys)
            }
            fn visit_i64<E>(self, _: i64) -> Result<UniqueKeys, E> {
                Ok(UniqueKeys)
            }
            fn visit_u64<E>(self, _: u64) -> Result<UniqueKeys, E> {
                Ok(UniqueKeys)
            }
            fn visit_f64<E>(self, _: f64) -> Result<UniqueKeys, E> {
                Ok(UniqueKeys)
            }
            fn visit_str<E>(self, _: &str) -> Result<UniqueKeys, E> {
                Ok(UniqueKeys)
            }
            fn visit_unit<E>(self) -> Result<UniqueKeys, E> {
                Ok(UniqueKeys)
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<UniqueKeys, A::Error> {
                while seq.next_element::<UniqueKeys>()?.is_some() {}
                Ok(UniqueKeys)
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<UniqueKeys, A::Error> {
                let mut seen = std::collections::HashSet::new();
                while let Some(key) = map.next_key::<String>()? {
                    map.next_value::<UniqueKeys>()?;
                    if !seen.insert(key.clone()) {
                        return Err(serde::de::Error::custom(format!("`{key}` is given twice")));
                    }
                }
                Ok(UniqueKeys)
            }
        }
        d.deserialize_any(Visit)
    }
}

/// The first key given twice in one object of the JSON `text`, as a spec error
/// naming its path (`problem.gamma`).
pub(super) fn duplicate_key(text: &str) -> Option<SpecError> {
    let mut de = serde_json::Deserializer::from_str(text);
    let e = serde_path_to_error::deserialize::<_, UniqueKeys>(&mut de).err()?;
    let mut path = steps(e.path());
    let message = e.into_inner().to_string();
    // the path ends at the object; the key opens the message
    if let Some((key, _)) = message.strip_prefix('`').and_then(|m| m.split_once("` is given twice")) {
        path.push(Step::Key(key.to_string()));
    }
    Some(SpecError::new(render(&path), message))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_key_given_twice_is_named() {
        let e =
            duplicate_key(r#"{"problem": {"type": "curvature_flow", "gamma": 1, "gamma": 2}, "initial": {}}"#).unwrap();
        assert_eq!(e.field, "problem.gamma", "{e}");
        assert!(e.message.contains("given twice"), "{e}");
        let e = duplicate_key(r#"{"problem": {}, "problem": {}}"#).unwrap();
        assert_eq!(e.field, "problem", "{e}");
        let e = duplicate_key(r#"{"initial": {"shape": "union", "parts": [{"r": 1}, {"r": 1, "r": 2}]}}"#).unwrap();
        assert_eq!(e.field, "initial.parts[1].r", "{e}");
        assert!(duplicate_key(r#"{"a": {"b": 1}, "c": {"b": 1}}"#).is_none());
    }
}
