//! An orientation as a caller names it (its kind, with the settings of
//! every kind beside it, as a command line gives them) made into an
//! [`Orientation`]: a viewpoint given under the automatic kind asks for
//! orientation toward it, a sensor hint is for the automatic kind only, a
//! viewpoint for the viewpoint kind only (the unoriented kind ignores it),
//! and `tau` and the source direction must hold whatever the kind.

use super::{BadNormalParameter, NormalsError, Orientation, Sensor};
use glam::DVec3;

/// The orientation asked for, by kind (its settings apart, in
/// [`OrientationChoice`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum OrientationKind {
    /// [`Orientation::Auto`].
    #[default]
    #[value(help = "From what the scan knows: stations, up (aerial), else the spanning tree")]
    Auto,
    /// [`Orientation::SpanningTree`].
    #[value(
        name = "mst",
        help = "Minimum spanning tree over the Riemannian graph (paper 1)"
    )]
    SpanningTree,
    /// [`Orientation::Aerial`].
    #[value(help = "Up (+z), the spanning tree where a surface turns past vertical (aerial)")]
    Aerial,
    /// [`Orientation::Stations`].
    #[value(help = "Toward each point's own scan station (E57 scan poses)")]
    Stations,
    /// [`Orientation::Viewpoint`].
    #[value(help = "Toward --viewpoint")]
    Viewpoint,
    /// [`Orientation::SixSources`].
    #[value(
        name = "sources",
        help = "Six sources at the extreme points along +-X, +-Y, +-Z (paper 5)"
    )]
    SixSources,
    /// [`Orientation::SingleSource`].
    #[value(help = "One source, the point farthest along --source-direction (terrain)")]
    SingleSource,
    /// [`Orientation::None`].
    #[value(help = "Unoriented (canonical PCA sign)")]
    None,
}

/// An orientation's kind and the settings the kinds take, each used by
/// the kinds that take it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrientationChoice {
    /// The kind asked for.
    pub kind: OrientationKind,
    /// What took the scan: a hint to [`OrientationKind::Auto`] only.
    pub sensor: Sensor,
    /// The scanner position: [`OrientationKind::Viewpoint`] needs it, and
    /// with [`OrientationKind::Auto`] it asks for that kind.
    pub viewpoint: Option<DVec3>,
    /// Least `|n_i . n_j|` across which a source's orientation spreads,
    /// in `[0, 1]`.
    pub tau: f64,
    /// The direction the single source is farthest along (not zero).
    pub direction: DVec3,
}

impl Default for OrientationChoice {
    fn default() -> Self {
        OrientationChoice {
            kind: OrientationKind::Auto,
            sensor: Sensor::Auto,
            viewpoint: None,
            tau: super::sources::DEFAULT_TAU,
            direction: DVec3::Z,
        }
    }
}

impl OrientationChoice {
    /// The orientation chosen; an error says which settings do not go
    /// together, or which value is out of its range (checked in that
    /// order).
    pub fn orientation(&self) -> Result<Orientation, NormalsError> {
        self.chosen().map_err(NormalsError::BadParameter)
    }

    fn chosen(&self) -> Result<Orientation, BadNormalParameter> {
        use OrientationKind as Kind;
        if self.sensor != Sensor::Auto && self.kind != Kind::Auto {
            return Err(BadNormalParameter::SensorNotAuto);
        }
        let orientation = match (self.kind, self.viewpoint) {
            (Kind::Viewpoint, None) => return Err(BadNormalParameter::NoViewpoint),
            (Kind::Auto | Kind::Viewpoint, Some(v)) => Orientation::Viewpoint(v),
            (Kind::Auto, None) => Orientation::Auto(self.sensor),
            (Kind::None, _) => Orientation::None,
            (_, Some(_)) => return Err(BadNormalParameter::ViewpointNotAsked),
            (Kind::SpanningTree, None) => Orientation::SpanningTree,
            (Kind::Aerial, None) => Orientation::Aerial,
            (Kind::Stations, None) => Orientation::Stations,
            (Kind::SixSources, None) => Orientation::SixSources { tau: self.tau },
            (Kind::SingleSource, None) => Orientation::SingleSource {
                direction: self.direction,
                tau: self.tau,
            },
        };
        if !(0.0..=1.0).contains(&self.tau) {
            return Err(BadNormalParameter::Tau(self.tau));
        }
        if self.direction.try_normalize().is_none() {
            return Err(BadNormalParameter::Direction(self.direction));
        }
        Ok(orientation)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn choose(kind: OrientationKind) -> OrientationChoice {
        OrientationChoice {
            kind,
            ..OrientationChoice::default()
        }
    }

    #[test]
    fn a_viewpoint_under_auto_asks_for_it_and_none_ignores_it() {
        let v = DVec3::new(1.0, 2.0, 3.0);
        let with = |kind| OrientationChoice {
            viewpoint: Some(v),
            ..choose(kind)
        };
        assert_eq!(
            with(OrientationKind::Auto).chosen(),
            Ok(Orientation::Viewpoint(v))
        );
        assert_eq!(with(OrientationKind::None).chosen(), Ok(Orientation::None));
        assert_eq!(
            with(OrientationKind::SpanningTree).chosen(),
            Err(BadNormalParameter::ViewpointNotAsked)
        );
        assert_eq!(
            choose(OrientationKind::Viewpoint).chosen(),
            Err(BadNormalParameter::NoViewpoint)
        );
    }

    #[test]
    fn settings_that_do_not_go_together_are_refused_in_order() {
        let sensor_and_tau = OrientationChoice {
            sensor: Sensor::Aerial,
            tau: 2.0,
            ..choose(OrientationKind::Aerial)
        };
        assert_eq!(
            sensor_and_tau.chosen(),
            Err(BadNormalParameter::SensorNotAuto)
        );
        let tau_and_direction = OrientationChoice {
            tau: 2.0,
            direction: DVec3::ZERO,
            ..choose(OrientationKind::Auto)
        };
        assert_eq!(
            tau_and_direction.chosen(),
            Err(BadNormalParameter::Tau(2.0))
        );
        let direction = OrientationChoice {
            direction: DVec3::ZERO,
            ..choose(OrientationKind::SpanningTree)
        };
        assert_eq!(
            direction.chosen(),
            Err(BadNormalParameter::Direction(DVec3::ZERO))
        );
        assert_eq!(
            OrientationChoice::default().chosen(),
            Ok(Orientation::Auto(Sensor::Auto))
        );
    }
}
