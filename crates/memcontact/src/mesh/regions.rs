//! Region names: the key `default` (the value of every region a table does not name, and
//! the name of the triangles or boundary edges no region covers), and the names that region
//! tables cannot address plainly.

use std::collections::BTreeMap;

/// The region-table key of every region not named in the table, and the name of the
/// triangles (or boundary edges) that no named region covers.
pub const DEFAULT: &str = "default";

/// Warnings about region names that region tables cannot address plainly: a region other
/// than tag 0 named `"default"` (the key of every other region's value), an empty name, or
/// a number
/// that is another region's tag (its key would be ambiguous, and is refused by
/// [`crate::field::Field::bind`]). `tags` are the region tags of the mesh (repetitions are fine).
pub fn region_name_warnings(names: &BTreeMap<u32, String>, tags: &[u32]) -> Vec<String> {
    let mut warnings = Vec::new();
    let mut present = tags.to_vec();
    present.sort_unstable();
    present.dedup();
    let is_tag = |t: u32| present.binary_search(&t).is_ok() || names.contains_key(&t);
    for (&tag, n) in names {
        // Tag 0 named "default" is this program's own convention (the triangles outside
        // every named polygon region): the default value is indeed its value.
        if n == DEFAULT && tag != 0 {
            warnings.push(format!(
                "physical surface {tag} is named \"{DEFAULT}\", the region-table key \
                 of the value of every other region: give its own value under the key \
                 \"{tag}\" (its tag), or rename it"
            ));
        } else if n.trim().is_empty() {
            warnings.push(format!(
                "physical surface {tag} has an empty name: region tables reach it by its \
                 tag, \"{tag}\""
            ));
        } else if let Ok(other) = n.trim().parse::<u32>() {
            if other != tag && is_tag(other) {
                warnings.push(format!(
                    "physical surface {tag} is named \"{n}\", which is also the tag of \
                     physical surface {other}: a region-table key \"{n}\" is ambiguous and \
                     is refused; rename the surface"
                ));
            }
        }
    }
    warnings
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ambiguous_region_names_are_warned_about_and_refused() {
        // Tag 5 is named "2", and tag 2 exists: the key "2" could mean either.
        let names = BTreeMap::from([
            (2, "clay".to_string()),
            (5, "2".to_string()),
            (6, "default".to_string()),
            (7, String::new()),
            (8, "8".to_string()),
        ]);
        let tags = [2, 5, 6, 7, 8, 2];
        let w = region_name_warnings(&names, &tags);
        assert_eq!(w.len(), 3, "{w:?}");
        assert!(
            w[0].contains("surface 5") && w[0].contains("ambiguous"),
            "{w:?}"
        );
        assert!(
            w[1].contains("surface 6") && w[1].contains("\"6\""),
            "{w:?}"
        );
        assert!(
            w[2].contains("surface 7") && w[2].contains("empty"),
            "{w:?}"
        );
    }
}
