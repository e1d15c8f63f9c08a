//! The range checks of [`ImplicitParams`]: what the library refuses before
//! it reads a point (the CLI maps each refusal to its flag).

use super::reconstruct::{ImplicitParams, ReconError};

impl ImplicitParams {
    /// Refuses a cell that is not positive and finite, a noise bound that
    /// is negative or not finite, a flat tolerance that is negative or not
    /// finite, a small-piece share outside `[0, 1]`, and
    /// normal parameters that cannot give normals.
    pub fn validate(&self) -> Result<(), ReconError> {
        if let Some(cell) = self.cell {
            if !(cell.is_finite() && cell > 0.0) {
                return Err(ReconError::BadParameter {
                    what: "cell",
                    value: cell,
                });
            }
        }
        if let Some(noise) = self.noise {
            if !(noise.is_finite() && noise >= 0.0) {
                return Err(ReconError::BadParameter {
                    what: "noise",
                    value: noise,
                });
            }
        }
        if let Some(t) = self.flat_tolerance {
            if !(t.is_finite() && t >= 0.0) {
                return Err(ReconError::BadFlatTolerance(t));
            }
        }
        self.min_piece_share()?;
        Ok(self.normals.validate()?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_values_are_refused_with_typed_errors() {
        let d = ImplicitParams::default();
        for cell in [f64::NAN, 0.0, -1.0, f64::INFINITY] {
            let p = ImplicitParams {
                cell: Some(cell),
                ..d
            };
            assert!(
                matches!(
                    p.validate(),
                    Err(ReconError::BadParameter { what: "cell", .. })
                ),
                "cell {cell} accepted"
            );
        }
        for noise in [f64::NAN, -0.5] {
            let p = ImplicitParams {
                noise: Some(noise),
                ..d
            };
            assert!(
                matches!(
                    p.validate(),
                    Err(ReconError::BadParameter { what: "noise", .. })
                ),
                "noise {noise} accepted"
            );
        }
        for share in [f64::NAN, -0.1, 1.5] {
            let p = ImplicitParams {
                min_piece: Some(share),
                ..d
            };
            assert!(
                matches!(p.validate(), Err(ReconError::BadShare(_))),
                "{share}"
            );
        }
        let mut p = d;
        p.normals.k = 0;
        assert!(matches!(p.validate(), Err(ReconError::Normals(_))));
        let ok = ImplicitParams {
            cell: Some(0.1),
            noise: Some(0.0),
            min_piece: Some(0.01),
            ..d
        };
        assert!(ok.validate().is_ok() && d.validate().is_ok());
    }
}
