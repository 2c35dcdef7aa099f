//! The files of a sensitivity run and of a fit: `sensitivity.csv` (one row per output and
//! parameter), `fit.json` (the fitted parameters and their statistics), `fit.csv` (one
//! row per iteration) and `fit.png` (drawn by the picture crate), and the result set that
//! holds them with the solve's files ([`write_sensitivity_result`]). Written atomically,
//! numbers in their shortest round-trip form and NaN as an empty field, like the other CSV
//! files.

use super::pictures::{outcome_pictures, write_png};
use super::result::{write_result_set_with, Extras};
use super::WriteOptions;
use crate::case::Case;
use crate::error::Result;
use crate::fit::FitResult;
use crate::io::numbers::push_shortest;
use crate::mesh::Mesh;
use crate::outcome::fields::NodalFields;
use crate::outcome::{Outcome, SensitivityTotals, Summary};
use crate::sensitivity::Sensitivities;
use memcontact_plot::{render_fit_plot, FitPlot, FitSensor, PlotOptions, Units};
use std::path::Path;

/// The file name of the derivatives table.
pub const SENSITIVITY_CSV: &str = "sensitivity.csv";

/// The file name of the fit's result.
pub const FIT_JSON: &str = "fit.json";

/// The file name of the fit's iterations.
pub const FIT_CSV: &str = "fit.csv";

/// The columns of `sensitivity.csv`, in order. The first five are a contract: the output,
/// the parameter (a case key), the output's value Q, the derivative dQ/dp and the
/// elasticity (p/Q) dQ/dp (empty for an offset, p = 0 or Q = 0). Then: the one-sided
/// derivatives (toward +δp, and minus the one toward −δp) where biactive vertices make
/// them differ (empty elsewhere), `biactive` 1 on those rows, the parameter's kind
/// (`value`, `factor`, `offset`) and its value in the case (1 for a factor, 0 for an
/// offset).
pub const SENSITIVITY_COLUMNS: [&str; 10] = [
    "output",
    "parameter",
    "value",
    "derivative",
    "elasticity",
    "derivative_plus",
    "derivative_minus",
    "biactive",
    "parameter_kind",
    "parameter_value",
];

/// A text field of a CSV row (quoted when it holds a comma, a quote or a line break).
fn push_text(buf: &mut Vec<u8>, s: &str) {
    if s.contains([',', '"', '\n', '\r']) {
        buf.push(b'"');
        buf.extend_from_slice(s.replace('"', "\"\"").as_bytes());
        buf.push(b'"');
    } else {
        buf.extend_from_slice(s.as_bytes());
    }
}

/// A number (NaN: an empty field; ±∞: `inf`, `-inf`).
fn push_number(buf: &mut Vec<u8>, x: f64) {
    if x.is_finite() {
        push_shortest(buf, x);
    } else if x.is_infinite() {
        buf.extend_from_slice(if x > 0.0 { b"inf" } else { b"-inf" });
    }
}

/// Writes `sensitivity.csv` of `s` to `path` (see [`SENSITIVITY_COLUMNS`]).
pub fn write_sensitivity_csv(path: &Path, s: &Sensitivities) -> Result<crate::io::Written> {
    let mut buf = Vec::new();
    buf.extend_from_slice(SENSITIVITY_COLUMNS.join(",").as_bytes());
    buf.push(b'\n');
    let np = s.parameters.len();
    for (o, name) in s.outputs.iter().enumerate() {
        for (p, key) in s.parameters.iter().enumerate() {
            let k = o * np + p;
            push_text(&mut buf, name);
            buf.push(b',');
            push_text(&mut buf, &key.key);
            buf.push(b',');
            push_number(&mut buf, s.values[o]);
            buf.push(b',');
            push_number(&mut buf, s.derivative[k]);
            buf.push(b',');
            push_number(&mut buf, s.elasticity(o, p));
            buf.push(b',');
            if s.nonsmooth[k] {
                push_number(&mut buf, s.derivative_plus[k]);
                buf.push(b',');
                push_number(&mut buf, s.derivative_minus[k]);
            } else {
                buf.push(b',');
            }
            buf.push(b',');
            buf.push(if s.nonsmooth[k] { b'1' } else { b'0' });
            buf.push(b',');
            buf.extend_from_slice(key.kind.name().as_bytes());
            buf.push(b',');
            push_number(&mut buf, key.value);
            buf.push(b'\n');
        }
    }
    crate::io::write_atomic(path, |w| w.write_all(&buf))
}

/// Writes `fit.json`: the parameters (key → fitted value), their standard errors, start
/// values and bounds, the correlation matrix (rows and columns in `parameter_names` order),
/// the singular values of the scaled Jacobian and its condition number, the rms of the
/// weighted residuals, the iterations, whether it converged and why it stopped, the
/// identifiability warning (null when none), and the measurements with the computed
/// values. A fit that did not converge is marked: `"converged": false` and
/// `"note"` saying the files hold its best iterate.
pub fn write_fit_json(path: &Path, fit: &FitResult) -> Result<()> {
    use serde_json::{json, Map, Value};
    let n = fit.parameters.len();
    let map = |f: &dyn Fn(usize) -> f64| -> Value {
        let mut m = Map::new();
        for (j, p) in fit.parameters.iter().enumerate() {
            m.insert(p.key.clone(), number(f(j)));
        }
        Value::Object(m)
    };
    let names: Vec<&str> = fit.parameters.iter().map(|p| p.key.as_str()).collect();
    let corr: Vec<Vec<Value>> = (0..n)
        .map(|j| {
            (0..n)
                .map(|k| number(fit.statistics.correlation[j * n + k]))
                .collect()
        })
        .collect();
    let measurements: Vec<Value> = fit
        .measurements
        .iter()
        .map(|m| {
            json!({
                "name": m.name,
                "x": number(m.at[0]),
                "y": number(m.at[1]),
                "measured": number(m.measured),
                "sigma": number(m.sigma),
                "computed": number(m.computed),
                "residual": number((m.computed - m.measured) / m.sigma),
            })
        })
        .collect();
    let value = json!({
        "parameters": map(&|j| fit.parameters[j].value),
        "std_errors": map(&|j| fit.parameters[j].std_error),
        "start": map(&|j| fit.parameters[j].start),
        "bounds": fit.parameters.iter().map(|p| (p.key.clone(), json!([number(p.bounds[0]), number(p.bounds[1])]))).collect::<Map<String, Value>>(),
        "log_scale": fit.parameters.iter().map(|p| (p.key.clone(), Value::Bool(p.log))).collect::<Map<String, Value>>(),
        "parameter_names": names,
        "correlation": corr,
        "singular_values": fit.statistics.singular_values.iter().map(|&v| number(v)).collect::<Vec<_>>(),
        "condition_number": number(fit.statistics.condition_number),
        "variance_factor": number(fit.statistics.variance_factor),
        "rms": number(fit.rms),
        "cost": number(fit.cost),
        "iterations": fit.iterations,
        "solves": fit.solves,
        "converged": fit.converged,
        "stop": fit.stop.name(),
        "warning": fit.statistics.warning,
        "note": if fit.converged { Value::Null } else { Value::String("the fit did not converge: these files hold its best iterate".into()) },
        "measurements": measurements,
        "seconds": number(fit.seconds),
        "seconds_solves": number(fit.seconds_solves),
        "seconds_derivatives": number(fit.seconds_derivatives),
        "forward_solves": fit.forward_solves.iter().map(|f| json!({
            "parameters": f.parameters.iter().map(|&v| number(v)).collect::<Vec<_>>(),
            "iterations": f.iterations,
            "seconds": number(f.seconds),
            "accepted": f.accepted,
        })).collect::<Vec<_>>(),
    });
    crate::io::json::write_json(path, &value)
}

/// A JSON number, or null for NaN and ±∞ (JSON has none).
fn number(x: f64) -> serde_json::Value {
    serde_json::Number::from_f64(x).map_or(serde_json::Value::Null, serde_json::Value::Number)
}

/// Writes `fit.csv`: `iteration`, the parameters (one column per key), `rms`, `step` (the
/// largest change of a fitted variable, ln p for a logarithmic one), `damping` and
/// `solves` (forward solves so far), one row per accepted iterate from the start.
pub fn write_fit_csv(path: &Path, fit: &FitResult) -> Result<()> {
    let mut buf = Vec::new();
    buf.extend_from_slice(b"iteration");
    for p in &fit.parameters {
        buf.push(b',');
        push_text(&mut buf, &p.key);
    }
    buf.extend_from_slice(b",rms,step,damping,solves\n");
    for h in &fit.history {
        buf.extend_from_slice(h.iteration.to_string().as_bytes());
        for &v in h.parameters.iter().chain([h.rms, h.step, h.damping].iter()) {
            buf.push(b',');
            push_number(&mut buf, v);
        }
        buf.push(b',');
        buf.extend_from_slice(h.solves.to_string().as_bytes());
        buf.push(b'\n');
    }
    crate::io::write_atomic(path, |w| w.write_all(&buf)).map(|_| ())
}

/// The file name of the fit's picture.
pub const FIT_PICTURE: &str = "fit.png";

/// Draws `fit.png` of `fit` into `path`: the measurements against the deflections computed
/// at the fitted parameters, and the residuals at the sensors over the outline of `mesh`,
/// titled `title`.
pub fn fit_picture(
    path: &Path,
    fit: &FitResult,
    mesh: &Mesh,
    title: &str,
    units: &Units,
) -> Result<()> {
    let sensors: Vec<FitSensor> = fit
        .measurements
        .iter()
        .map(|m| FitSensor {
            at: m.at,
            measured: m.measured,
            computed: m.computed,
        })
        .collect();
    let note = format!(
        "rms {:.3e}, {} iterations{}",
        fit.rms,
        fit.iterations,
        if fit.converged {
            ""
        } else {
            " (not converged)"
        }
    );
    let canvas = render_fit_plot(&FitPlot {
        title,
        note: &note,
        points: &mesh.points,
        triangles: &mesh.triangles,
        sensors: &sensors,
        units,
    })?;
    write_png(path, &canvas)
}

/// Writes the result set of a run with `[sensitivity]` or `[fit]` into `target`
/// atomically, as `memcontact solve` writes it: the solve's files and the pictures of
/// `plots` (`summary.json` recording them, with the sensitivity's totals), the influence
/// maps of `sensitivities` in `solution.vtu` and its `sensitivity.csv`, and the fit's
/// `fit.json`, `fit.csv` and (when `plots` draws any picture) `fit.png`.
/// `options.plot_options` is replaced by `plots`. Returns the summary written.
pub fn write_sensitivity_result(
    target: &Path,
    outcome: &Outcome,
    case: &Case,
    options: &WriteOptions,
    plots: &PlotOptions,
    sensitivities: Option<&Sensitivities>,
    fit: Option<&FitResult>,
) -> Result<Summary> {
    let options = WriteOptions {
        plot_options: serde_json::to_value(plots).ok(),
        ..options.clone()
    };
    let extras = Extras {
        point_data: sensitivities
            .map(|s| s.influence.clone())
            .unwrap_or_default(),
        sensitivity: sensitivities.map(SensitivityTotals::of),
    };
    let mesh = outcome.mesh();
    let mut maps = outcome_pictures(outcome, plots);
    let title = format!("Fit: {}", plots.title.as_deref().unwrap_or(&options.label));
    let mut extra = |dir: &Path, fields: &NodalFields| -> Result<Vec<String>> {
        let mut names = maps(dir, fields)?;
        if let Some(s) = sensitivities {
            write_sensitivity_csv(&dir.join(SENSITIVITY_CSV), s)?;
            names.push(SENSITIVITY_CSV.to_string());
        }
        if let Some(f) = fit {
            write_fit_json(&dir.join(FIT_JSON), f)?;
            write_fit_csv(&dir.join(FIT_CSV), f)?;
            names.push(FIT_JSON.to_string());
            names.push(FIT_CSV.to_string());
            if !plots.plots.is_empty() {
                fit_picture(&dir.join(FIT_PICTURE), f, &mesh, &title, &plots.units)?;
                names.push(FIT_PICTURE.to_string());
            }
        }
        Ok(names)
    };
    write_result_set_with(target, outcome, case, &options, &mut extra, &extras)
}
