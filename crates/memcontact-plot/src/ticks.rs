//! "Nice" numbers: tick positions, contour levels and their labels.

/// The nice step (1, 2, 2.5 or 5 times a power of ten) that cuts `[lo, hi]` into at most
/// about `count` intervals.
pub fn nice_step(lo: f64, hi: f64, count: usize) -> f64 {
    let span = (hi - lo).abs();
    if span.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) || !span.is_finite() {
        return 1.0;
    }
    let raw = span / count.max(1) as f64;
    let p = 10f64.powf(raw.log10().floor());
    for m in [1.0, 2.0, 2.5, 5.0, 10.0] {
        if m * p >= raw * (1.0 - 1e-9) {
            return m * p;
        }
    }
    10.0 * p
}

/// Multiples of `step` inside `[lo, hi]` (ends included up to rounding).
pub fn multiples(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    if step.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        || !lo.is_finite()
        || !hi.is_finite()
        || hi < lo
    {
        return Vec::new();
    }
    let eps = 1e-9 * step;
    let k0 = ((lo - eps) / step).ceil() as i64;
    let k1 = ((hi + eps) / step).floor() as i64;
    if k1 - k0 > 10_000 {
        return Vec::new();
    }
    (k0..=k1)
        .map(|k| {
            let v = k as f64 * step;
            if v.abs() < 1e-12 * step {
                0.0
            } else {
                v
            }
        })
        .collect()
}

/// Nice tick positions in `[lo, hi]`, at most about `count` of them.
pub fn ticks(lo: f64, hi: f64, count: usize) -> (Vec<f64>, f64) {
    let step = nice_step(lo, hi, count);
    (multiples(lo, hi, step), step)
}

/// Contour levels: nice values strictly inside `(lo, hi)`, about `count` of them.
pub fn levels(lo: f64, hi: f64, count: usize) -> Vec<f64> {
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return Vec::new();
    }
    let step = nice_step(lo, hi, count + 1);
    let eps = 1e-6 * (hi - lo);
    multiples(lo, hi, step)
        .into_iter()
        .filter(|&v| v > lo + eps && v < hi - eps)
        .collect()
}

/// Formats `v` as a label among values spaced `step` apart: enough decimals to tell
/// neighbours apart, scientific notation for very large or small magnitudes.
pub fn format(v: f64, step: f64) -> String {
    if v == 0.0 || v.abs() < 1e-9 * step.abs() {
        return "0".into();
    }
    let mag = v.abs().max(step.abs());
    if !(1e-4..1e6).contains(&mag) {
        // digits after the point of the mantissa: enough for the step
        let e = v.abs().log10().floor();
        let d = ((e - step.abs().log10().floor()).max(0.0) as usize).min(6);
        return format!("{v:.d$e}");
    }
    let mut d = (-step.abs().log10().floor()).max(0.0) as usize;
    // 2.5-type steps need one more decimal
    let m = step.abs() / 10f64.powi(-(d as i32));
    if (m.round() - m).abs() > 1e-6 {
        d += 1;
    }
    let d = d.min(10);
    let s = format!("{v:.d$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        "0".into()
    } else {
        s
    }
}

/// A value with about `sig` significant digits (for range labels such as "max 2.0312").
pub fn format_sig(v: f64, sig: usize) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v.is_finite() {
            "0".into()
        } else {
            format!("{v}")
        };
    }
    let e = v.abs().log10().floor() as i32;
    if !(-4..6).contains(&e) {
        return format!("{:.*e}", sig.saturating_sub(1), v);
    }
    let d = (sig as i32 - 1 - e).max(0) as usize;
    let s = format!("{v:.d$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_ticks_and_labels() {
        let (t, s) = ticks(0.0, 1.0, 5);
        assert_eq!(s, 0.2);
        assert_eq!(t.len(), 6);
        assert_eq!(format(t[3], s), "0.6");
        let (t, s) = ticks(-0.13, 2.07, 6);
        assert_eq!(s, 0.5);
        assert_eq!(t, vec![0.0, 0.5, 1.0, 1.5, 2.0]);
        assert_eq!(format(0.25, 0.25), "0.25");
        assert_eq!(format(12.0, 2.0), "12");
        assert_eq!(format(3e-7, 1e-7), "3e-7");
        assert_eq!(format(1.5e-7, 5e-8), "1.5e-7");
        let l = levels(0.0, 2.03, 8);
        assert_eq!(l.first(), Some(&0.25));
        assert!(l.iter().all(|&v| v > 0.0 && v < 2.03));
        assert!(levels(1.0, 1.0, 5).is_empty());
        assert_eq!(format_sig(2.031234, 5), "2.0312");
        assert_eq!(format_sig(-0.000123456, 3), "-0.000123");
    }
}
