//! The model's side of Dahl friction ([`crate::element::Dahl`]): its states along the
//! path, and adding it to the frames with friction (`--dahl`). An algorithm over the
//! model and its workspace, like the dynamics: the element knows neither, and the model
//! does not depend on the workspace it sizes.

use crate::element::{Dahl, Element};
use crate::error::ModelError;
use crate::param::{Param, ParamKind};
use crate::workspace::Workspace;

use crate::model::Model;

/// The model's side of Dahl friction: its states along the path, and adding it to the
/// frames with friction (`--dahl`).
impl Model {
    /// Moves the hysteresis states of the workspace (the [`Dahl`](Dahl) elements')
    /// along the path to positions `q` (rad or m, model coordinates) from the positions of
    /// the previous call, exactly for a path monotone between the two ([`Dahl::step`](Dahl::step)):
    /// call it once per sample, in time order, before the regressor or the dynamics of
    /// that sample. The first call after [`Workspace::new`] or
    /// [`Workspace::reset_hysteresis`] only records `q` (the states stay 0). A model
    /// without Dahl elements does nothing. Allocates nothing.
    ///
    /// ```
    /// # use dvrk_model::{Model, Workspace};
    /// let psm = Model::builtin("psm").unwrap().with_dahl(20.0).unwrap();
    /// let mut ws = Workspace::new(&psm);
    /// psm.advance_hysteresis(&mut ws, &[0.0; 7]);
    /// psm.advance_hysteresis(&mut ws, &[0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    /// let fd1 = psm.param_names().iter().position(|n| n == "Fd1").unwrap();
    /// // From 0 over 0.1 rad: z = 1 − exp(−20·0.1).
    /// assert!((ws.hysteresis()[fd1] - (1.0 - (-2.0f64).exp())).abs() < 1e-12);
    /// ```
    pub fn advance_hysteresis(&self, ws: &mut Workspace, q: &[f64]) {
        ws.check(self);
        assert_eq!(q.len(), self.dof(), "q must have length {}", self.dof());
        for (value, column, sigma) in &self.element_plan.hysteresis {
            let s = value.eval(q);
            let at = ws.hysteresis_at[*column];
            if !at.is_nan() {
                let z = ws.hysteresis[*column];
                ws.hysteresis[*column] = Dahl::step(z, s - at, *sigma);
            }
            ws.hysteresis_at[*column] = s;
        }
    }

    /// The parameter columns of the Dahl elements (where their states are kept in the
    /// workspace), in frame order; empty when the model has none.
    pub fn hysteresis_columns(&self) -> Vec<usize> {
        self.element_plan
            .hysteresis
            .iter()
            .map(|(_, c, _)| *c)
            .collect()
    }

    /// Adds Dahl friction of stiffness `sigma` (1/rad or 1/m) on frame `frame` (1-based);
    /// its `Fd{frame}` parameter is appended to the parameter vector. Errors if the frame
    /// has no friction element, already has a Dahl element, or `sigma` is not positive
    /// and finite.
    pub fn add_dahl(&mut self, frame: usize, sigma: f64) -> Result<(), ModelError> {
        let numeric = |message: String| ModelError::Numeric {
            model: self.name.clone(),
            message,
        };
        let sigma = Dahl::check_sigma(sigma).map_err(|e| numeric(e.to_string()))?;
        let p = self.params.len();
        let Some(f) = frame.checked_sub(1).and_then(|i| self.frames.get_mut(i)) else {
            return Err(numeric(format!("no frame {frame}")));
        };
        let name = f.name.clone();
        if f.friction().is_none() {
            return Err(numeric(format!(
                "frame {frame} ({name}) has no friction to add Dahl friction to"
            )));
        }
        if f.elements.iter().any(|e| matches!(e, Element::Dahl(_))) {
            return Err(numeric(format!(
                "frame {frame} ({name}) already has Dahl friction"
            )));
        }
        f.elements.push(Element::Dahl(Dahl { param: p, sigma }));
        self.params.push(Param {
            name: format!("Fd{frame}"),
            kind: ParamKind::Dahl,
            frame,
        });
        self.element_plan = self.derive_element_plan();
        Ok(())
    }

    /// This model with Dahl friction of stiffness `sigma` (1/rad or 1/m) on every frame
    /// with friction and no Dahl element yet (e.g. `dvrk-ident fit --dahl 20`), the `Fd`
    /// parameters appended in frame order.
    ///
    /// ```
    /// let psm = dvrk_model::Model::builtin("psm").unwrap();
    /// let with = psm.with_dahl(20.0).unwrap();
    /// assert_eq!(with.n_params(), psm.n_params() + 10);
    /// assert_eq!(with.param_names()[psm.n_params()], "Fd1");
    /// assert!(psm.with_dahl(0.0).is_err() && psm.with_dahl(f64::NAN).is_err());
    /// ```
    pub fn with_dahl(&self, sigma: f64) -> Result<Model, ModelError> {
        let mut m = self.clone();
        Dahl::check_sigma(sigma).map_err(|e| ModelError::Numeric {
            model: m.name.clone(),
            message: e.to_string(),
        })?;
        let frames: Vec<usize> = (1..=m.frames.len())
            .filter(|&i| {
                let f = &m.frames[i - 1];
                f.friction().is_some() && !f.elements.iter().any(|e| matches!(e, Element::Dahl(_)))
            })
            .collect();
        for i in frames {
            m.add_dahl(i, sigma)?;
        }
        Ok(m)
    }
}
