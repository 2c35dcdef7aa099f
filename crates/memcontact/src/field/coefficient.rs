//! What assembly asks of a datum: its value at a point of a region, and whether it is
//! constant on a region (then exact element integrals replace quadrature).

use crate::mesh::Point;

/// A coefficient (f, h, ...) that assembly can evaluate.
pub trait Coefficient: Sync {
    /// The value at point `p` inside a triangle of region `region`.
    fn at(&self, p: Point, region: u32) -> f64;
    /// The value on a whole region, when constant there (assembly then uses exact
    /// closed-form element integrals instead of quadrature).
    fn on_region(&self, region: u32) -> Option<f64>;
    /// The values at `points` of a triangle of region `region` into `out` (of the same
    /// length): [`Coefficient::at`] at each, or what gives the same values faster.
    fn at_points(&self, points: &[Point], region: u32, out: &mut [f64]) {
        for (o, &p) in out.iter_mut().zip(points) {
            *o = self.at(p, region);
        }
    }
}

impl Coefficient for f64 {
    fn at(&self, _: Point, _: u32) -> f64 {
        *self
    }
    fn on_region(&self, _: u32) -> Option<f64> {
        Some(*self)
    }
}

/// A coefficient given by a closure of the point (tests, manufactured loads).
pub struct FnCoefficient<F: Fn(Point) -> f64 + Sync>(pub F);

impl<F: Fn(Point) -> f64 + Sync> Coefficient for FnCoefficient<F> {
    fn at(&self, p: Point, _: u32) -> f64 {
        (self.0)(p)
    }
    fn on_region(&self, _: u32) -> Option<f64> {
        None
    }
}
