//! The expression compiler and evaluator: any text either parses or is refused with a
//! message; a parsed expression evaluates at any point without panicking, a constant
//! expression evaluates to its constant everywhere, and evaluating many points at once
//! gives each point's own value.
#![no_main]

use libfuzzer_sys::fuzz_target;
use memcontact::field::Expr;

fuzz_target!(|data: &[u8]| {
    // The first 16 bytes pick the point; the rest is the expression.
    if data.len() < 16 {
        return;
    }
    let x = f64::from_le_bytes(data[..8].try_into().unwrap());
    let y = f64::from_le_bytes(data[8..16].try_into().unwrap());
    let Ok(text) = std::str::from_utf8(&data[16..]) else {
        return;
    };
    match Expr::parse(text) {
        Ok(e) => {
            let v = e.eval(x, y);
            let w = e.eval(0.5, -0.25);
            if let Some(c) = e.constant_value() {
                assert!(v.to_bits() == c.to_bits() && w.to_bits() == c.to_bits());
            }
            // Evaluation is a pure function of the point.
            assert_eq!(e.eval(x, y).to_bits(), v.to_bits());
            // Many points at once give each point's value (a NaN is any NaN).
            let mut many = [0.0; 2];
            e.eval_many(&[[x, y], [0.5, -0.25]], &mut many);
            for (m, one) in many.into_iter().zip([v, w]) {
                assert!(m.to_bits() == one.to_bits() || (m.is_nan() && one.is_nan()));
            }
        }
        Err(err) => {
            // Messages stay short whatever the input's length.
            assert!(
                err.to_string().len() < 2000,
                "{} bytes",
                err.to_string().len()
            );
        }
    }
});
