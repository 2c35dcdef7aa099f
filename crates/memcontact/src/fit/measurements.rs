//! The measurements file of `[fit]` (`measurements = "points.csv"`): a CSV table with the
//! header `name,x,y,u` (in any order) and optionally `sigma`, one measured deflection per
//! row. Blank lines and lines starting with `#` are skipped. Each row becomes a sensor
//! with its measurement; errors name the line and the column.

use crate::case::Sensor;
use crate::error::{Error, Result};
use std::path::Path;

/// The largest measurements file read (bytes).
pub const MEASUREMENTS_CAP: u64 = 16 << 20;

/// The most rows of a measurements file.
pub const MAX_MEASUREMENTS: usize = 100_000;

/// Parses the text of a measurements file into sensors with `measured` (and `sigma`)
/// values; an error is `(line, message)` (1-based line).
pub fn parse_measurements(text: &str) -> std::result::Result<Vec<Sensor>, (usize, String)> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let (hl, header) = lines.next().ok_or((
        1,
        "the file is empty: give the header name,x,y,u (and sigma)".to_string(),
    ))?;
    let names: Vec<String> = header
        .split(',')
        .map(|c| c.trim().to_ascii_lowercase())
        .collect();
    let col = |want: &str| names.iter().position(|c| c == want);
    let (Some(cn), Some(cx), Some(cy), Some(cu)) = (col("name"), col("x"), col("y"), col("u"))
    else {
        return Err((
            hl,
            format!("the header must name the columns name, x, y, u (and optionally sigma), got \"{header}\""),
        ));
    };
    let cs = col("sigma");
    for (i, c) in names.iter().enumerate() {
        if !["name", "x", "y", "u", "sigma"].contains(&c.as_str()) {
            return Err((
                hl,
                format!("unknown column \"{c}\" (columns: name, x, y, u, sigma)"),
            ));
        }
        if names[..i].contains(c) {
            return Err((hl, format!("column \"{c}\" is given twice")));
        }
    }
    let mut out: Vec<Sensor> = Vec::new();
    for (line, l) in lines {
        if out.len() >= MAX_MEASUREMENTS {
            return Err((line, format!("more than {MAX_MEASUREMENTS} measurements")));
        }
        let fields: Vec<&str> = l.split(',').map(str::trim).collect();
        if fields.len() != names.len() {
            return Err((
                line,
                format!(
                    "{} fields, the header has {} columns",
                    fields.len(),
                    names.len()
                ),
            ));
        }
        let number = |c: usize| -> std::result::Result<f64, (usize, String)> {
            let f = fields[c];
            f.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or((
                line,
                format!("column {}: \"{f}\" is not a finite number", names[c]),
            ))
        };
        let sigma = match cs {
            Some(c) if !fields[c].is_empty() => {
                let s = number(c)?;
                if s <= 0.0 {
                    return Err((line, format!("column sigma: must be > 0, got {s}")));
                }
                Some(s)
            }
            _ => None,
        };
        let sensor = Sensor {
            name: fields[cn].to_string(),
            at: [number(cx)?, number(cy)?],
            measured: Some(number(cu)?),
            sigma,
        };
        crate::case::sensitivity::check_sensor("", &sensor).map_err(|e| (line, e.message))?;
        if out.iter().any(|s| s.name == sensor.name) {
            return Err((
                line,
                format!("sensor \"{}\" is measured twice", sensor.name),
            ));
        }
        out.push(sensor);
    }
    if out.is_empty() {
        return Err((hl, "no measurements after the header".into()));
    }
    Ok(out)
}

/// Reads a measurements file (a regular file of at most 16 MiB,
/// UTF-8); errors name the file, the line and the key `fit.measurements`.
pub fn read_measurements(path: &Path) -> Result<Vec<Sensor>> {
    let kind = crate::io::input::InputKind {
        cap: MEASUREMENTS_CAP,
        what: "a measurements file (CSV text)",
    };
    let bytes = crate::io::input::read_input(path, kind)?;
    let text = String::from_utf8(bytes).map_err(|e| Error::File {
        path: path.to_path_buf(),
        message: format!(
            "is not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        ),
    })?;
    parse_measurements(&text).map_err(|(line, message)| Error::Case {
        file: Some(path.to_path_buf()),
        line: Some(line),
        key: "fit.measurements".into(),
        message,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_become_measured_sensors() {
        let s = parse_measurements(
            "# site survey\nname,x,y,u,sigma\nA,0.1,0.2,-0.01,0.001\n\nB, 1, 0.5, 0.02,\n",
        )
        .unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].at, [0.1, 0.2]);
        assert_eq!(s[0].sigma, Some(0.001));
        assert_eq!(s[1].measured, Some(0.02));
        assert_eq!(s[1].sigma, None);
        let s = parse_measurements("u,y,x,name\n1,2,3,P\n").unwrap();
        assert_eq!((s[0].at, s[0].measured), ([3.0, 2.0], Some(1.0)));
    }

    #[test]
    fn bad_files_name_the_line() {
        for (text, line, what) in [
            ("", 1, "empty"),
            ("name,x,y\nA,1,2\n", 1, "header"),
            ("name,x,y,u,depth\nA,1,2,3,4\n", 1, "unknown column"),
            ("name,x,y,u\nA,1,2\n", 2, "fields"),
            ("name,x,y,u\nA,1,nan,3\n", 2, "finite"),
            ("name,x,y,u,sigma\nA,1,2,3,-1\n", 2, "> 0"),
            ("name,x,y,u\nA,1,2,3\nA,2,2,3\n", 3, "twice"),
            ("name,x,y,u\nA B,1,2,3\n", 2, "sensor name"),
            ("name,x,y,u\n", 1, "no measurements"),
        ] {
            let (l, m) = parse_measurements(text).unwrap_err();
            assert_eq!(l, line, "{text:?}: {m}");
            assert!(m.contains(what), "{text:?}: {m}");
        }
    }
}
