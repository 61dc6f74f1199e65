//! Numbers and expressions of a hand-written file resolved against its constants and
//! coordinates, each failure named by file, place and field (descriptions and limits).

use crate::error::ModelError;
use crate::expr::{Affine, Expr, NumOrExpr, Scope};
use crate::input;

pub(crate) struct Ctx<'a> {
    pub file: &'a str,
    pub constants: Vec<(String, f64)>,
    pub coordinates: &'a [String],
}

impl Ctx<'_> {
    pub(crate) fn scope(&self) -> Scope<'_> {
        Scope {
            constants: &self.constants,
            coordinates: self.coordinates,
        }
    }

    pub(crate) fn expr(&self, place: &str, field: &str, text: &str) -> Result<Expr, ModelError> {
        Expr::parse(text, &self.scope())
            .map_err(|e| ModelError::field(self.file, place, field, e.to_string()))
    }

    /// A number or constant expression, finite and at most `max` (`unit`) in magnitude.
    pub(crate) fn number(
        &self,
        place: &str,
        field: &str,
        v: &NumOrExpr,
        (max, unit): (f64, &str),
    ) -> Result<f64, ModelError> {
        let x = match v {
            NumOrExpr::Num(x) => *x,
            NumOrExpr::Expr(s) => self
                .expr(place, field, s)?
                .constant_value(self.coordinates)
                .map_err(|e| ModelError::field(self.file, place, field, e.to_string()))?,
        };
        input::check_magnitude(x, max, unit)
            .map_err(|m| ModelError::field(self.file, place, field, m))
    }

    /// An affine joint value whose offset is at most `max` (`unit`) and whose
    /// coefficients are at most [`input::MAX_ANGLE_RAD`] in magnitude, all finite.
    pub(crate) fn affine(
        &self,
        place: &str,
        field: &str,
        v: &NumOrExpr,
        (max, unit): (f64, &str),
    ) -> Result<Affine, ModelError> {
        let a = match v {
            NumOrExpr::Num(x) => Affine::constant(*x),
            NumOrExpr::Expr(s) => self
                .expr(place, field, s)?
                .affine(self.coordinates.len())
                .map_err(|e| ModelError::field(self.file, place, field, e.to_string()))?,
        };
        let bad = |m: String| ModelError::field(self.file, place, field, m);
        input::check_magnitude(a.offset, max, unit).map_err(|e| bad(e.to_string()))?;
        for &(k, c) in &a.terms {
            input::check_magnitude(c, input::MAX_ANGLE_RAD, "")
                .map_err(|m| bad(format!("coefficient of {}: {m}", self.coordinates[k])))?;
        }
        Ok(a)
    }

    pub(crate) fn range(
        &self,
        place: &str,
        field: &str,
        v: &Option<[NumOrExpr; 2]>,
        range: (f64, &str),
    ) -> Result<Option<[f64; 2]>, ModelError> {
        let Some([lo, hi]) = v else { return Ok(None) };
        let lo = self.number(place, field, lo, range)?;
        let hi = self.number(place, field, hi, range)?;
        if lo > hi {
            return Err(ModelError::field(
                self.file,
                place,
                field,
                format!("lower bound {lo} is above upper bound {hi}"),
            ));
        }
        Ok(Some([lo, hi]))
    }
}
