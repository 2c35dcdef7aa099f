//! Manufactured solutions: smooth functions with their exact derivatives
//! (docs/theory.md#manufactured-solutions).

use super::solution::ExactSolution;
use crate::error::{Error, Result};
use std::f64::consts::PI;

#[derive(Debug, Clone, Copy)]
pub(super) enum Shape {
    Rectangle { x0: f64, y0: f64, x1: f64, y1: f64 },
    Disk { center: [f64; 2], radius: f64 },
}

/// Manufactured solutions (docs/theory.md#manufactured-solutions): smooth functions
/// vanishing on ∂Ω, with exact gradient and Laplacian. The caller sets `f = -t Δu + h (u -
/// φ)⁺` (see [`super::manufactured_load`]).
#[derive(Debug, Clone, Copy)]
pub struct Manufactured {
    pub(super) shape: Shape,
    pub(super) amplitude: f64,
}

impl Manufactured {
    /// On the rectangle `[x0, x1] × [y0, y1]`:
    /// `u = A sin(π (x - x0)/(x1 - x0)) sin(π (y - y0)/(y1 - y0))`,
    /// `Δu = -π² (1/(x1-x0)² + 1/(y1-y0)²) u`.
    ///
    /// Errors: non-finite data, `x1 ≤ x0` or `y1 ≤ y0`.
    pub fn rectangle(x0: f64, y0: f64, x1: f64, y1: f64, amplitude: f64) -> Result<Manufactured> {
        if ![x0, y0, x1, y1, amplitude].iter().all(|v| v.is_finite()) {
            return Err(Error::Data(format!(
                "manufactured rectangle [{x0}, {x1}] × [{y0}, {y1}], amplitude {amplitude}: \
                 data must be finite"
            )));
        }
        if x1 <= x0 || y1 <= y0 {
            return Err(Error::Data(format!(
                "manufactured rectangle [{x0}, {x1}] × [{y0}, {y1}] is empty"
            )));
        }
        Ok(Manufactured {
            shape: Shape::Rectangle { x0, y0, x1, y1 },
            amplitude,
        })
    }

    /// On the disc `|x - c| < R`, with `X = (x - cx)/R`, `Y = (y - cy)/R`:
    /// `u = A (1 - X² - Y²)(1 + X/2)` (not radial), `Δu = -4A (1 + X)/R²`.
    ///
    /// Errors: non-finite data or `radius ≤ 0`.
    pub fn disk(center: [f64; 2], radius: f64, amplitude: f64) -> Result<Manufactured> {
        if ![center[0], center[1], radius, amplitude]
            .iter()
            .all(|v| v.is_finite())
            || radius <= 0.0
        {
            return Err(Error::Data(format!(
                "manufactured disc centre ({}, {}), radius {radius}, amplitude {amplitude}: \
                 data must be finite and the radius > 0",
                center[0], center[1]
            )));
        }
        Ok(Manufactured {
            shape: Shape::Disk { center, radius },
            amplitude,
        })
    }
}

impl ExactSolution for Manufactured {
    fn value(&self, p: [f64; 2]) -> f64 {
        let a = self.amplitude;
        match self.shape {
            Shape::Rectangle { x0, y0, x1, y1 } => {
                let (sx, sy) = (
                    (PI * (p[0] - x0) / (x1 - x0)).sin(),
                    (PI * (p[1] - y0) / (y1 - y0)).sin(),
                );
                a * sx * sy
            }
            Shape::Disk { center, radius } => {
                let (x, y) = ((p[0] - center[0]) / radius, (p[1] - center[1]) / radius);
                a * (1.0 - x * x - y * y) * (1.0 + 0.5 * x)
            }
        }
    }

    fn gradient(&self, p: [f64; 2]) -> [f64; 2] {
        let a = self.amplitude;
        match self.shape {
            Shape::Rectangle { x0, y0, x1, y1 } => {
                let (lx, ly) = (x1 - x0, y1 - y0);
                let (ax, ay) = (PI * (p[0] - x0) / lx, PI * (p[1] - y0) / ly);
                [
                    a * PI / lx * ax.cos() * ay.sin(),
                    a * PI / ly * ax.sin() * ay.cos(),
                ]
            }
            Shape::Disk { center, radius } => {
                let (x, y) = ((p[0] - center[0]) / radius, (p[1] - center[1]) / radius);
                [
                    a * (0.5 - 2.0 * x - 0.5 * (3.0 * x * x + y * y)) / radius,
                    a * (-2.0 * y - x * y) / radius,
                ]
            }
        }
    }

    fn laplacian(&self, p: [f64; 2]) -> f64 {
        let a = self.amplitude;
        match self.shape {
            Shape::Rectangle { x0, y0, x1, y1 } => {
                let (lx, ly) = (x1 - x0, y1 - y0);
                -PI * PI * (1.0 / (lx * lx) + 1.0 / (ly * ly)) * self.value(p)
            }
            Shape::Disk { center, radius } => {
                let x = (p[0] - center[0]) / radius;
                -4.0 * a * (1.0 + x) / (radius * radius)
            }
        }
    }

    fn contains(&self, p: [f64; 2]) -> bool {
        match self.shape {
            Shape::Rectangle { x0, y0, x1, y1 } => {
                let tol = 1e-10 * (x1 - x0).max(y1 - y0);
                p[0] >= x0 - tol && p[0] <= x1 + tol && p[1] >= y0 - tol && p[1] <= y1 + tol
            }
            Shape::Disk { center, radius } => {
                (p[0] - center[0]).hypot(p[1] - center[1]) <= radius * (1.0 + 1e-10)
            }
        }
    }

    fn disk(&self) -> Option<([f64; 2], f64)> {
        match self.shape {
            Shape::Disk { center, radius } => Some((center, radius)),
            Shape::Rectangle { .. } => None,
        }
    }

    fn describe(&self) -> String {
        match self.shape {
            Shape::Rectangle { x0, y0, x1, y1 } => format!(
                "manufactured A sin sin on [{x0}, {x1}] × [{y0}, {y1}], A = {}",
                self.amplitude
            ),
            Shape::Disk { center, radius } => format!(
                "manufactured A (1 - r²/R²)(1 + (x - cx)/(2R)) on the disc (centre ({}, {}), \
                 R = {radius}), A = {}",
                center[0], center[1], self.amplitude
            ),
        }
    }
}

/// A manufactured solution with zero normal derivative on every side of a rectangle, so
/// that any side may be free (the natural condition holds there) and the others fixed at
/// `g = u`: `u = A (cos(πX) cos(πY) + ½ cos(2πY))` with `X = (x − x0)/(x1 − x0)`,
/// `Y = (y − y0)/(y1 − y0)`; `u` ranges over `[−¾A, 3/2 A]`.
#[derive(Debug, Clone, Copy)]
pub struct ManufacturedCosine {
    pub(super) x0: f64,
    pub(super) y0: f64,
    pub(super) lx: f64,
    pub(super) ly: f64,
    pub(super) amplitude: f64,
}

impl ManufacturedCosine {
    /// On the rectangle `[x0, x1] × [y0, y1]`. Errors: non-finite data, an empty rectangle.
    pub fn rectangle(x0: f64, y0: f64, x1: f64, y1: f64, amplitude: f64) -> Result<Self> {
        Manufactured::rectangle(x0, y0, x1, y1, amplitude)?;
        Ok(ManufacturedCosine {
            x0,
            y0,
            lx: x1 - x0,
            ly: y1 - y0,
            amplitude,
        })
    }
}

impl ExactSolution for ManufacturedCosine {
    fn value(&self, p: [f64; 2]) -> f64 {
        let (ax, ay) = (
            PI * (p[0] - self.x0) / self.lx,
            PI * (p[1] - self.y0) / self.ly,
        );
        self.amplitude * (ax.cos() * ay.cos() + 0.5 * (2.0 * ay).cos())
    }

    fn gradient(&self, p: [f64; 2]) -> [f64; 2] {
        let (ax, ay) = (
            PI * (p[0] - self.x0) / self.lx,
            PI * (p[1] - self.y0) / self.ly,
        );
        let a = self.amplitude;
        [
            -a * PI / self.lx * ax.sin() * ay.cos(),
            -a * PI / self.ly * (ax.cos() * ay.sin() + (2.0 * ay).sin()),
        ]
    }

    fn laplacian(&self, p: [f64; 2]) -> f64 {
        let (ax, ay) = (
            PI * (p[0] - self.x0) / self.lx,
            PI * (p[1] - self.y0) / self.ly,
        );
        let (kx, ky) = (PI / self.lx, PI / self.ly);
        -self.amplitude
            * ((kx * kx + ky * ky) * ax.cos() * ay.cos() + 2.0 * ky * ky * (2.0 * ay).cos())
    }

    fn contains(&self, p: [f64; 2]) -> bool {
        let tol = 1e-10 * self.lx.max(self.ly);
        p[0] >= self.x0 - tol
            && p[0] <= self.x0 + self.lx + tol
            && p[1] >= self.y0 - tol
            && p[1] <= self.y0 + self.ly + tol
    }

    fn describe(&self) -> String {
        format!(
            "manufactured A (cos(πX) cos(πY) + ½ cos(2πY)) on [{}, {}] × [{}, {}] (zero normal \
             derivative on every side), A = {}",
            self.x0,
            self.x0 + self.lx,
            self.y0,
            self.y0 + self.ly,
            self.amplitude
        )
    }
}
