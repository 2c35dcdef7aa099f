//! The measurements file of `[fit]` (`name,x,y,u[,sigma]` CSV text): any bytes are refused
//! with a line number or give sensors whose names, points and values pass the sensors'
//! own checks.
#![no_main]

use libfuzzer_sys::fuzz_target;
use memcontact::fit::parse_measurements;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match parse_measurements(text) {
        Ok(sensors) => {
            assert!(!sensors.is_empty());
            for (i, s) in sensors.iter().enumerate() {
                assert!(s.at.iter().all(|v| v.is_finite()));
                assert!(s.measured.is_some_and(f64::is_finite));
                assert!(s.sigma.is_none_or(|v| v.is_finite() && v > 0.0));
                assert!(sensors[..i].iter().all(|o| o.name != s.name));
            }
        }
        Err((line, message)) => {
            assert!(line >= 1 && line <= text.lines().count().max(1));
            assert!(!message.is_empty());
        }
    }
});
