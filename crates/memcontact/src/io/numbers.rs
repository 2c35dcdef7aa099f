//! Numbers as text, the one form every text file of memcontact writes them in, and the
//! borrowed arrays the writers take.

/// A borrowed data array for a VTU file (one component per vertex or per triangle).
#[derive(Debug, Clone, Copy)]
pub enum DataArray<'a> {
    /// 64-bit floats (VTK `Float64`).
    F64(&'a [f64]),
    /// 32-bit signed integers (VTK `Int32`), e.g. region tags or vertex indices.
    I32(&'a [i32]),
    /// 8-bit signed integers (VTK `Int8`), e.g. flags such as "in contact".
    I8(&'a [i8]),
}

impl DataArray<'_> {
    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            DataArray::F64(v) => v.len(),
            DataArray::I32(v) => v.len(),
            DataArray::I8(v) => v.len(),
        }
    }

    /// True when the array holds no value.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Appends the finite `x` in the shortest form that reads back to the same `f64`, with
/// exponents written without a plus sign (`1e16`, `2.5e-7`), the form of every text file
/// memcontact writes.
pub fn push_shortest(buf: &mut Vec<u8>, x: f64) {
    // Zero, the most frequent value of the contact columns (every clear vertex), without
    // the formatter: the same text it writes.
    if x == 0.0 {
        buf.extend_from_slice(if x.is_sign_negative() {
            b"-0.0"
        } else {
            b"0.0"
        });
        return;
    }
    let mut b = zmij::Buffer::new();
    let text = b.format_finite(x).as_bytes();
    // Only numbers of magnitude 1e16 and more are written with a positive exponent.
    if x.abs() < 1e15 {
        buf.extend_from_slice(text);
        return;
    }
    match text.iter().position(|&c| c == b'+') {
        Some(k) => {
            buf.extend_from_slice(&text[..k]);
            buf.extend_from_slice(&text[k + 1..]);
        }
        None => buf.extend_from_slice(text),
    }
}

/// Appends the decimal digits of `x`, as `{x}` writes them, without the formatting
/// machinery (state and region columns are a million integers and more).
pub fn push_int(buf: &mut Vec<u8>, x: i64) {
    if x < 0 {
        buf.push(b'-');
    }
    let mut n = x.unsigned_abs();
    let mut digits = [0u8; 20];
    let mut k = digits.len();
    loop {
        k -= 1;
        digits[k] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    buf.extend_from_slice(&digits[k..]);
}

#[cfg(any(test, feature = "bench"))]
/// CPU time of this process (user + system, all threads) from /proc, NaN elsewhere: wall
/// times are unreliable on a loaded machine.
pub(crate) fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // Fields after the command name (which is in parentheses): utime, stime are 14, 15.
    let after = &stat[stat.rfind(')').unwrap() + 2..];
    let f: Vec<f64> = after
        .split(' ')
        .skip(11)
        .take(2)
        .map(|x| x.parse().unwrap())
        .collect();
    (f[0] + f[1]) / 100.0
}
