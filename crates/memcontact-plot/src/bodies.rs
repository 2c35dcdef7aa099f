//! The pictures of a case with a body below (the membrane between two bodies): the contact
//! zones, pressures and coverage of both bodies drawn together, the same way when solving
//! and when redrawing from `solution.vtu`.

/// One body's fields over the vertices.
#[derive(Debug, Clone, Copy)]
pub struct BodyFields<'a> {
    /// Its surface.
    pub phi: &'a [f64],
    /// −1 clear, 0 touching, 1 penetrating.
    pub state: &'a [i8],
    /// Its contact pressure (≥ 0).
    pub pressure: &'a [f64],
    /// Where it lies against the membrane.
    pub covered: &'a [bool],
}

/// Both bodies' fields merged for the pictures: a vertex is in contact when it touches
/// either body, the pressure is the sum of the two (at most one acts, except where the
/// membrane is squeezed between them), the coverage is either body's, and the surface
/// drawn is the obstacle's, or the body below's when the obstacle covers nothing.
#[derive(Debug, Clone, Default)]
pub struct Merged {
    /// The surface drawn in the profile.
    pub phi: Vec<f64>,
    /// Contact with either body.
    pub state: Vec<i8>,
    /// The summed pressures.
    pub pressure: Vec<f64>,
    /// Either body's coverage.
    pub covered: Vec<bool>,
}

/// Merges the obstacle's fields with the body below's.
pub fn merge(upper: BodyFields, lower: BodyFields) -> Merged {
    let upper_acts = upper.covered.iter().any(|&c| c);
    Merged {
        phi: if upper_acts { upper.phi } else { lower.phi }.to_vec(),
        state: upper
            .state
            .iter()
            .zip(lower.state)
            .map(|(&a, &b)| a.max(b))
            .collect(),
        pressure: upper
            .pressure
            .iter()
            .zip(lower.pressure)
            .map(|(a, b)| a + b)
            .collect(),
        covered: upper
            .covered
            .iter()
            .zip(lower.covered)
            .map(|(&a, &b)| a || b)
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contact_with_either_body_shows() {
        let up = BodyFields {
            phi: &[1.0, 1.0, 1.0],
            state: &[-1, 0, -1],
            pressure: &[0.0, 2.0, 0.0],
            covered: &[true, true, false],
        };
        let low = BodyFields {
            phi: &[-1.0, -1.0, -1.0],
            state: &[1, -1, -1],
            pressure: &[3.0, 0.0, 0.0],
            covered: &[true, false, false],
        };
        let m = merge(up, low);
        assert_eq!(m.state, [1, 0, -1]);
        assert_eq!(m.pressure, [3.0, 2.0, 0.0]);
        assert_eq!(m.covered, [true, true, false]);
        assert_eq!(m.phi, [1.0, 1.0, 1.0]);
        // An obstacle that covers nothing: the body below's surface is drawn.
        let none = BodyFields {
            covered: &[false, false, false],
            ..up
        };
        assert_eq!(merge(none, low).phi, [-1.0, -1.0, -1.0]);
    }
}
