//! Quadrature rules on triangles in barycentric coordinates.

/// A quadrature point: barycentric coordinates and weight (weights sum to 1; multiply by
/// the triangle's area).
pub type QuadPoint = ([f64; 3], f64);

/// Edge-midpoint rule, exact for degree 2 (a check of the test of exactness).
#[cfg(test)]
const DEGREE2: [QuadPoint; 3] = [
    ([0.5, 0.5, 0.0], 1.0 / 3.0),
    ([0.0, 0.5, 0.5], 1.0 / 3.0),
    ([0.5, 0.0, 0.5], 1.0 / 3.0),
];

const A1: f64 = 0.059_715_871_789_769_82;
const B1: f64 = 0.470_142_064_105_115_1;
const W1: f64 = 0.132_394_152_788_506_2;
const A2: f64 = 0.797_426_985_353_087_3;
const B2: f64 = 0.101_286_507_323_456_3;
const W2: f64 = 0.125_939_180_544_827_1;

/// Dunavant's 7-point rule, exact for polynomials of degree 5.
pub const DEGREE5: [QuadPoint; 7] = [
    ([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], 0.225),
    ([A1, B1, B1], W1),
    ([B1, A1, B1], W1),
    ([B1, B1, A1], W1),
    ([A2, B2, B2], W2),
    ([B2, A2, B2], W2),
    ([B2, B2, A2], W2),
];

/// The Cartesian point of barycentric coordinates `b` in the triangle `c`.
pub fn map(c: &[[f64; 2]; 3], b: &[f64; 3]) -> [f64; 2] {
    [
        b[0] * c[0][0] + b[1] * c[1][0] + b[2] * c[2][0],
        b[0] * c[0][1] + b[1] * c[1][1] + b[2] * c[2][1],
    ]
}

/// `P_n(z)` and `P_n'(z)` by the three-term recurrence of the Legendre polynomials.
fn legendre(n: usize, z: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, z);
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * z * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    (p1, n as f64 * (z * p1 - p0) / (z * z - 1.0))
}

/// Gauss-Legendre points and weights on [-1, 1] (Newton's method on the Legendre
/// polynomial `P_n`, from the Chebyshev-like initial guesses).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        for _ in 0..100 {
            let (p, dp) = legendre(n, z);
            let dz = p / dp;
            z -= dz;
            if dz.abs() <= 1e-16 {
                break;
            }
        }
        let (_, dp) = legendre(n, z);
        x[i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
    (x, w)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ over the reference triangle of λ1^a λ2^b λ3^c = a! b! c! 2! / (a+b+c+2)! × area.
    fn exact(a: u32, b: u32, c: u32) -> f64 {
        let f = |n: u32| (1..=n).map(|k| k as f64).product::<f64>();
        f(a) * f(b) * f(c) * 2.0 / f(a + b + c + 2)
    }

    #[test]
    fn degree5_is_exact_for_all_monomials_up_to_degree_5() {
        for a in 0..=5 {
            for b in 0..=(5 - a) {
                for c in 0..=(5 - a - b) {
                    let q: f64 = DEGREE5
                        .iter()
                        .map(|(l, w)| {
                            w * l[0].powi(a as i32) * l[1].powi(b as i32) * l[2].powi(c as i32)
                        })
                        .sum();
                    assert!((q - exact(a, b, c)).abs() < 1e-15, "{a} {b} {c}");
                }
            }
        }
        let q: f64 = DEGREE2.iter().map(|(l, w)| w * l[0] * l[1]).sum();
        assert!((q - exact(1, 1, 0)).abs() < 1e-15);
    }
}
