//! CSV writers: per-vertex columns (one row per index) and small tables (histories,
//! convergence studies).
//!
//! Conventions, the same for both writers:
//! * comma-separated, `\n` line ends, one header row of column names (quoted per RFC 4180
//!   only when a name holds a comma, a quote or a line break);
//! * floats in the shortest form that reads back to the same `f64` (`0.1`, `1e-7`, `-0.0`),
//!   so a file round-trips exactly;
//! * NaN is written as an **empty field** (read as missing/NaN by pandas, numpy's
//!   `genfromtxt`, R and spreadsheets); infinities as `inf` and `-inf`;
//! * integers in decimal.
//!
//! Files are written atomically ([`crate::io::write_atomic`]).

use super::numbers::{push_int, push_shortest, DataArray};
use crate::error::{Error, Result};
use rayon::prelude::*;
use std::path::Path;

/// Writes `columns` side by side: a header row with the names, then row `i` holding value
/// `i` of every column. All columns must have the same length ([`Error::Data`] naming the
/// first column that differs otherwise); at least one column is required.
pub fn write_columns_csv(path: &Path, columns: &[(&str, DataArray)]) -> Result<crate::io::Written> {
    let Some((first, first_data)) = columns.first() else {
        return Err(Error::Data(format!(
            "CSV {}: no column to write",
            path.display()
        )));
    };
    let rows = first_data.len();
    if let Some((name, data)) = columns.iter().find(|(_, d)| d.len() != rows) {
        return Err(Error::Data(format!(
            "CSV column `{name}` has {} values, column `{first}` has {rows}",
            data.len()
        )));
    }
    let names: Vec<&str> = columns.iter().map(|(n, _)| *n).collect();
    crate::io::write_atomic(path, |w| {
        let mut head = Vec::new();
        push_header(&mut head, &names);
        w.write_all(&head)?;
        // Blocks of rows are formatted in parallel, a batch at a time, and written in order;
        // a batch is written while the next one is formatted.
        let blocks = rows.div_ceil(ROWS_PER_BLOCK);
        let batch = 4 * rayon::current_num_threads().max(1);
        let format_batch = |first: usize| -> Vec<Vec<u8>> {
            (first..(first + batch).min(blocks))
                .into_par_iter()
                .map(|b| {
                    let range = b * ROWS_PER_BLOCK..((b + 1) * ROWS_PER_BLOCK).min(rows);
                    format_rows(columns, range)
                })
                .collect()
        };
        let mut texts = format_batch(0);
        let mut next = batch;
        while !texts.is_empty() {
            let mut following = Vec::new();
            rayon::in_place_scope(|s| {
                if next < blocks {
                    s.spawn(|_| following = format_batch(next));
                }
                texts.iter().try_for_each(|t| w.write_all(t))
            })?;
            texts = following;
            next += batch;
        }
        Ok(())
    })
}

/// Rows per block formatted by one task.
const ROWS_PER_BLOCK: usize = 4096;

/// Formats rows `range` of `columns` as CSV lines.
fn format_rows(columns: &[(&str, DataArray)], range: std::ops::Range<usize>) -> Vec<u8> {
    let mut buf = Vec::with_capacity(range.len() * columns.len() * 20);
    for i in range {
        for (k, (_, data)) in columns.iter().enumerate() {
            if k > 0 {
                buf.push(b',');
            }
            match data {
                DataArray::F64(v) => push_f64(&mut buf, v[i]),
                DataArray::I32(v) => push_int(&mut buf, v[i] as i64),
                DataArray::I8(v) => push_int(&mut buf, v[i] as i64),
            }
        }
        buf.push(b'\n');
    }
    buf
}

fn push_header(buf: &mut Vec<u8>, names: &[&str]) {
    for (k, name) in names.iter().enumerate() {
        if k > 0 {
            buf.push(b',');
        }
        if name.contains([',', '"', '\n', '\r']) {
            buf.push(b'"');
            buf.extend_from_slice(name.replace('"', "\"\"").as_bytes());
            buf.push(b'"');
        } else {
            buf.extend_from_slice(name.as_bytes());
        }
    }
    buf.push(b'\n');
}

/// Appends `x` in its shortest round-trip form; NaN as nothing (an empty field).
fn push_f64(buf: &mut Vec<u8>, x: f64) {
    if x.is_finite() {
        push_shortest(buf, x);
    } else if x.is_nan() {
        // empty field
    } else if x > 0.0 {
        buf.extend_from_slice(b"inf");
    } else {
        buf.extend_from_slice(b"-inf");
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn tmp(name: &str) -> crate::io::TmpPath {
        crate::io::TmpPath::new(name)
    }

    /// Parses a field written by these writers back to f64 (empty = NaN).
    fn parse(s: &str) -> f64 {
        if s.is_empty() {
            f64::NAN
        } else {
            s.parse().unwrap()
        }
    }

    fn same(x: f64, y: f64) -> bool {
        x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan())
    }

    #[test]
    fn integers_are_written_as_rust_formats_them() {
        let mut xs: Vec<i64> = (-1000..1000).collect();
        xs.extend([i64::MIN, i64::MIN + 1, i64::MAX, 10, 99, 100, -10, 1 << 40]);
        xs.extend((0..19).map(|k| 10i64.pow(k)));
        for x in xs {
            let mut buf = b"a".to_vec();
            push_int(&mut buf, x);
            assert_eq!(buf, format!("a{x}").into_bytes(), "{x}");
        }
    }

    #[test]
    fn columns_round_trip_exactly() {
        let u = [
            0.1 + 0.2,
            -0.0,
            1e-300,
            f64::MAX,
            f64::NAN,
            f64::NEG_INFINITY,
            5e-324,
        ];
        let flag: [i8; 7] = [0, 1, -1, 127, -128, 0, 1];
        let id: [i32; 7] = [0, 1, 2, i32::MAX, i32::MIN, 5, 6];
        let path = tmp("cols.csv");
        write_columns_csv(
            &path,
            &[
                ("u", DataArray::F64(&u)),
                ("flag", DataArray::I8(&flag)),
                ("id, \"vertex\"", DataArray::I32(&id)),
            ],
        )
        .unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next().unwrap(), r#"u,flag,"id, ""vertex""""#);
        let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
        assert_eq!(rows.len(), 7);
        for (i, r) in rows.iter().enumerate() {
            assert_eq!(r.len(), 3, "row {i}");
            assert!(same(parse(r[0]), u[i]), "row {i}: {}", r[0]);
            assert_eq!(r[1].parse::<i8>().unwrap(), flag[i]);
            assert_eq!(r[2].parse::<i32>().unwrap(), id[i]);
        }
        assert_eq!(rows[4][0], "", "NaN is an empty field");
        assert_eq!(rows[5][0], "-inf");
        assert!(text.ends_with('\n'));
        std::fs::remove_file(&path).unwrap();
    }

    /// The shortest round-trip form: parses back to the same bits, has as many significant
    /// digits as the standard library's own shortest form (`{:e}`), and no `+` in exponents.
    #[test]
    fn shortest_form_round_trips_with_the_fewest_digits() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut values = vec![0.1, 1e16, 1e-7, 1e22, 5e-324, f64::MAX, -0.0, 123456789.0];
        for k in 0..200_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let x = match k % 3 {
                0 => f64::from_bits(state),
                1 => (state >> 11) as f64 * 2f64.powi(-53),
                _ => (state % 100_000) as f64 * 10f64.powi((state % 60) as i32 - 30),
            };
            if x.is_finite() {
                values.push(x);
            }
        }
        let digits = |s: &str| {
            let mantissa = s.split(['e', 'E']).next().unwrap();
            let d: String = mantissa.chars().filter(|c| c.is_ascii_digit()).collect();
            d.trim_start_matches('0').trim_end_matches('0').len().max(1)
        };
        let mut buf = Vec::new();
        for &x in &values {
            buf.clear();
            push_shortest(&mut buf, x);
            let text = std::str::from_utf8(&buf).unwrap();
            assert!(same(text.parse().unwrap(), x), "{x:e} written {text}");
            assert!(!text.contains('+'), "{text}");
            assert_eq!(
                digits(text),
                digits(&format!("{x:e}")),
                "{x:e} written {text}"
            );
        }
        for (x, text) in [
            (0.1, "0.1"),
            (1e16, "1e16"),
            (1e-7, "1e-7"),
            (-0.0, "-0.0"),
            (0.0, "0.0"),
        ] {
            buf.clear();
            push_shortest(&mut buf, x);
            assert_eq!(std::str::from_utf8(&buf).unwrap(), text);
        }
        // Zero is written without the formatter: as the formatter writes it.
        for x in [0.0, -0.0] {
            buf.clear();
            push_shortest(&mut buf, x);
            let mut b = zmij::Buffer::new();
            assert_eq!(buf, b.format_finite(x).as_bytes());
        }
    }

    #[test]
    fn unequal_columns_are_named_and_leave_no_file() {
        let a = [1.0, 2.0];
        let b = [1i32];
        let path = tmp("bad.csv");
        let e = write_columns_csv(
            &path,
            &[("a", DataArray::F64(&a)), ("pressure", DataArray::I32(&b))],
        )
        .unwrap_err();
        assert!(
            matches!(&e, Error::Data(m) if m.contains("`pressure` has 1") && m.contains("`a` has 2")),
            "{e}"
        );
        assert!(write_columns_csv(&path, &[]).is_err());
        assert!(!path.exists());
    }

    #[test]
    #[ignore]
    fn csv_speed_one_million_rows() {
        let n = 1_000_000;
        let cols: Vec<Vec<f64>> = (0..10)
            .map(|c| {
                (0..n)
                    .map(|i| ((i * (c + 1)) as f64 * 1e-3).sin())
                    .collect()
            })
            .collect();
        let names: Vec<String> = (0..10).map(|c| format!("c{c}")).collect();
        let columns: Vec<(&str, DataArray)> = names
            .iter()
            .zip(&cols)
            .map(|(n, c)| (n.as_str(), DataArray::F64(c)))
            .collect();
        let path = tmp("speed.csv");
        let t = std::time::Instant::now();
        let cpu = crate::io::numbers::cpu_seconds();
        write_columns_csv(&path, &columns).unwrap();
        eprintln!(
            "CSV 1M rows x 10 f64 columns: {:.3} s wall, {:.2} s CPU (all threads), {:.1} MB",
            t.elapsed().as_secs_f64(),
            crate::io::numbers::cpu_seconds() - cpu,
            std::fs::metadata(&path).unwrap().len() as f64 / 1e6
        );
        let t = std::time::Instant::now();
        let cpu = crate::io::numbers::cpu_seconds();
        let bytes: usize = (0..n)
            .step_by(ROWS_PER_BLOCK)
            .map(|i| format_rows(&columns, i..(i + ROWS_PER_BLOCK).min(n)).len())
            .sum();
        eprintln!(
            "  formatting alone on one thread: {:.3} s wall, {:.2} s CPU ({bytes} bytes)",
            t.elapsed().as_secs_f64(),
            crate::io::numbers::cpu_seconds() - cpu
        );
        std::fs::remove_file(&path).unwrap();
    }
}
