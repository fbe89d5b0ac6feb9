//! The fit criteria and the one table of their names and aliases for the whole
//! package (the CLI, the Python API and the bindings all parse names here).

use gagekit_core::GkError;
use std::str::FromStr;

/// A fit criterion (ISO 12181 / ISO 12180 / ISO 1101 reference features).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FitCriterion {
    /// Geometric least squares (orthogonal distances, ASME B89.4.10).
    LeastSquares,
    /// Minimum circumscribed (Eqs. 6.1, 6.9, 6.13).
    MinCircumscribed,
    /// Maximum inscribed (Eqs. 6.2, 6.11, 6.15).
    MaxInscribed,
    /// Minimum zone (Chebyshev; Eqs. 6.5, 6.10, 6.14).
    MinZone,
}

/// Every accepted spelling (lower case, '-' for '_') and the criterion it names.
pub const ALIASES: &[(&str, FitCriterion)] = &[
    ("least-squares", FitCriterion::LeastSquares),
    ("lsq", FitCriterion::LeastSquares),
    ("ls", FitCriterion::LeastSquares),
    ("l2", FitCriterion::LeastSquares),
    ("gaussian", FitCriterion::LeastSquares),
    ("min-circumscribed", FitCriterion::MinCircumscribed),
    ("minimum-circumscribed", FitCriterion::MinCircumscribed),
    ("mc", FitCriterion::MinCircumscribed),
    ("mcc", FitCriterion::MinCircumscribed),
    ("mcs", FitCriterion::MinCircumscribed),
    ("max-inscribed", FitCriterion::MaxInscribed),
    ("maximum-inscribed", FitCriterion::MaxInscribed),
    ("mi", FitCriterion::MaxInscribed),
    ("mic", FitCriterion::MaxInscribed),
    ("mis", FitCriterion::MaxInscribed),
    ("minimum-zone", FitCriterion::MinZone),
    ("min-zone", FitCriterion::MinZone),
    ("mz", FitCriterion::MinZone),
    ("mzc", FitCriterion::MinZone),
    ("mzs", FitCriterion::MinZone),
    ("chebyshev", FitCriterion::MinZone),
];

impl FitCriterion {
    /// Every criterion, in the order of the documentation.
    pub const ALL: [FitCriterion; 4] =
        [Self::LeastSquares, Self::MinCircumscribed, Self::MaxInscribed, Self::MinZone];

    /// The canonical name (as the JSON output spells it).
    pub fn name(self) -> &'static str {
        match self {
            Self::LeastSquares => "least-squares",
            Self::MinCircumscribed => "min-circumscribed",
            Self::MaxInscribed => "max-inscribed",
            Self::MinZone => "minimum-zone",
        }
    }

    /// The short code of a 2-D circle fit (lsq, mc, mi, mz).
    pub fn code(self) -> &'static str {
        match self {
            Self::LeastSquares => "lsq",
            Self::MinCircumscribed => "mc",
            Self::MaxInscribed => "mi",
            Self::MinZone => "mz",
        }
    }

    /// Parse a name for a feature that admits only `allowed`; the error lists them.
    pub fn parse_for(name: &str, allowed: &[FitCriterion], shape: &str) -> Result<Self, GkError> {
        match name.parse::<FitCriterion>() {
            Ok(c) if allowed.contains(&c) => Ok(c),
            _ => Err(GkError::config(format!(
                "{shape}: unknown fit criterion {name:?}; choose one of {}",
                allowed.iter().map(|c| c.name()).collect::<Vec<_>>().join(", ")
            ))),
        }
    }
}

impl FromStr for FitCriterion {
    type Err = GkError;

    fn from_str(s: &str) -> Result<Self, GkError> {
        let key = s.trim().to_lowercase().replace('_', "-");
        ALIASES.iter().find(|(k, _)| *k == key).map(|(_, c)| *c).ok_or_else(|| {
            GkError::config(format!(
                "unknown fit criterion {s:?}; choose one of {}",
                Self::ALL.map(|c| c.name()).join(", ")
            ))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_alias_and_name_parses() {
        for (k, c) in ALIASES {
            assert_eq!(k.parse::<FitCriterion>().unwrap(), *c);
            assert_eq!(k.to_uppercase().replace('-', "_").parse::<FitCriterion>().unwrap(), *c);
        }
        for c in FitCriterion::ALL {
            assert_eq!(c.name().parse::<FitCriterion>().unwrap(), c);
            assert_eq!(c.code().parse::<FitCriterion>().unwrap(), c);
        }
        assert!("median".parse::<FitCriterion>().is_err());
        let e = FitCriterion::parse_for("mz", &[FitCriterion::LeastSquares], "cone").unwrap_err();
        assert!(e.message.contains("least-squares"), "{}", e.message);
    }
}
