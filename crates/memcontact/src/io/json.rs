//! JSON writer for summaries and reports.
//!
//! Non-finite floats never make an invalid file: a [`serde_json::Value`] cannot hold NaN or
//! ±∞ (`serde_json::json!(f64::NAN)` is already `null`), and any `f64` field of a
//! serialised struct that is NaN or infinite is written as `null` by serde_json. Readers
//! therefore see `null` where a value was not finite.

use crate::error::Result;
use std::path::Path;

/// Writes `value` pretty-printed (two-space indent) with a trailing newline, atomically.
///
/// `value` is usually a [`serde_json::Value`], but any [`serde::Serialize`] type works (a
/// results struct, a map, ...). Non-finite floats are written as `null` (see the module
/// documentation). A serialisation failure (e.g. a map with non-string keys) is reported as
/// [`crate::error::Error::Io`] and leaves no file.
pub fn write_json<T: serde::Serialize + ?Sized>(path: &Path, value: &T) -> Result<()> {
    crate::io::write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
    .map(|_| ())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn tmp(name: &str) -> crate::io::TmpPath {
        crate::io::TmpPath::new(name)
    }

    #[test]
    fn value_is_pretty_and_ends_with_newline() {
        let v = json!({"solver": "active-set", "iterations": 7, "energy": 0.1 + 0.2});
        let path = tmp("v.json");
        write_json(&path, &v).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.ends_with("}\n"), "{text}");
        assert!(text.contains("\n  \"iterations\": 7"), "{text}");
        let back: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(back, v);
        assert_eq!(back["energy"].as_f64().unwrap(), 0.1 + 0.2);
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn non_finite_floats_become_null() {
        #[derive(serde::Serialize)]
        struct Report {
            residual: f64,
            rates: Vec<f64>,
        }
        let r = Report {
            residual: f64::NAN,
            rates: vec![1.0, f64::INFINITY, f64::NEG_INFINITY],
        };
        let path = tmp("r.json");
        write_json(&path, &r).unwrap();
        let back: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert_eq!(back, json!({"residual": null, "rates": [1.0, null, null]}));
        let v = json!({"x": f64::NAN});
        write_json(&path, &v).unwrap();
        let back: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert!(back["x"].is_null());
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn serialisation_failure_leaves_no_file() {
        let mut m = std::collections::BTreeMap::new();
        m.insert(vec![1u8], 1.0);
        let path = tmp("bad.json");
        assert!(write_json(&path, &m).is_err());
        assert!(!path.exists());
    }
}
