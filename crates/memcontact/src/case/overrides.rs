//! `--set key=value` overrides of a case file's TOML, and the file:line:key spans of its
//! error messages.

/// Applies `key=value` overrides to TOML text, keeping the rest of the text (and so the
/// line numbers of untouched keys) as it is. Errors name the override.
pub fn apply_overrides(
    text: &str,
    overrides: &[String],
) -> std::result::Result<String, (String, String)> {
    if overrides.is_empty() {
        return Ok(text.to_string());
    }
    let mut doc: toml_edit::DocumentMut = text
        .parse()
        .map_err(|e: toml_edit::TomlError| (String::new(), e.message().to_string()))?;
    for set in overrides {
        let (key, value) = set.split_once('=').ok_or_else(|| {
            (
                set.clone(),
                "an override must be key=value, e.g. mesh.nx=64".to_string(),
            )
        })?;
        let key = key.trim();
        let parts: Vec<&str> = key.split('.').map(str::trim).collect();
        if parts.iter().any(|p| p.is_empty()) {
            return Err((key.to_string(), "malformed key".into()));
        }
        let value = value.trim();
        let parsed: toml_edit::Value = value
            .parse()
            .unwrap_or_else(|_| toml_edit::Value::from(value));
        let mut table = doc.as_table_mut();
        let mut k = 0;
        while k + 1 < parts.len() {
            let p = parts[k];
            // `name.N.key`: entry N of an array of tables (`[[name]]`).
            if table.get(p).is_some_and(|i| i.is_array_of_tables()) {
                let aot = table
                    .get_mut(p)
                    .and_then(|i| i.as_array_of_tables_mut())
                    .expect("an array of tables");
                let n = aot.len();
                let index = parts[k + 1]
                    .parse::<usize>()
                    .ok()
                    .filter(|_| k + 2 < parts.len());
                table = index.and_then(|i| aot.get_mut(i)).ok_or_else(|| {
                    (
                        key.to_string(),
                        format!(
                            "\"{p}\" is a list of {n} tables: name an entry's key by its index, \
                             e.g. {p}.0.name"
                        ),
                    )
                })?;
                k += 2;
                continue;
            }
            k += 1;
            let entry = table
                .entry(p)
                .or_insert_with(|| toml_edit::Item::Table(toml_edit::Table::new()));
            if let Some(inline) = entry.as_inline_table_mut() {
                let t = std::mem::take(inline).into_table();
                *entry = toml_edit::Item::Table(t);
            }
            table = entry
                .as_table_mut()
                .ok_or_else(|| (key.to_string(), format!("\"{p}\" is not a table")))?;
        }
        let last = parts[parts.len() - 1];
        match table.get_mut(last) {
            Some(item) if item.is_value() => {
                let decor = item.as_value().map(|v| v.decor().clone());
                let mut v = parsed;
                if let Some(d) = decor {
                    *v.decor_mut() = d;
                }
                *item = toml_edit::Item::Value(v);
            }
            _ => {
                table.insert(last, toml_edit::Item::Value(parsed));
            }
        }
    }
    Ok(doc.to_string())
}

/// The 1-based line of byte offset `at` in `text`.
pub(crate) fn line_of(text: &str, at: usize) -> usize {
    text.as_bytes()[..at.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// The span of the value of dotted `key` in TOML `text` (the deepest part found).
pub(crate) fn key_span(text: &str, key: &str) -> Option<std::ops::Range<usize>> {
    use toml::de::DeValue;
    let doc = toml::de::DeTable::parse(text).ok()?;
    let mut table = doc.get_ref();
    let mut span = None;
    let mut parts = key.split('.').peekable();
    'parts: while let Some(part) = parts.next() {
        let (_, mut v) = table.iter().find(|(k, _)| k.get_ref().as_ref() == part)?;
        span = Some(v.span());
        loop {
            match v.get_ref() {
                DeValue::Table(t) => {
                    table = t;
                    continue 'parts;
                }
                // `name.N`: element N of an array (an array of tables: `[[name]]`).
                DeValue::Array(a) => {
                    let element = parts
                        .peek()
                        .and_then(|p| p.parse::<usize>().ok())
                        .and_then(|i| a.get(i));
                    match element {
                        Some(e) => {
                            parts.next();
                            v = e;
                            span = Some(v.span());
                        }
                        None => break 'parts,
                    }
                }
                _ => break 'parts,
            }
        }
    }
    span
}

/// serde's messages name Rust types; a user reads "a number".
pub(crate) fn plain_types(message: &str) -> String {
    message
        .replace("expected f64", "expected a number")
        .replace("expected usize", "expected a non-negative integer")
        .replace("expected u32", "expected a non-negative integer")
        .replace("expected a sequence", "expected an array")
        .replace("expected a borrowed string", "expected a string")
}

/// serde_json's messages end with "at line 1 column 57": meaningless for a dict.
pub(crate) fn strip_json_position(message: &str) -> String {
    match message.rfind(" at line ") {
        Some(i) => message[..i].to_string(),
        None => message.to_string(),
    }
}
