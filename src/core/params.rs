//! Every tunable number of the method, with its default and its valid range.
//!
//! Lengths are in cells (the unit-cell frame of method.md §0), so the defaults hold for data in
//! metres, feet or degrees alike.

use serde::{Deserialize, Serialize};

/// How the Snake turns centroid forces into loads (method.md §4, "known weakness").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LoadModel {
    /// The paper's element loads (h/2·f, h²/12·f): long edges pull harder.
    Element,
    /// The force is applied at its node only, so crowded regions with short edges move as much as
    /// large ones.
    Nodal,
}

/// The parameters of one run. `Params::default()` is what the command line uses.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Params {
    /// α, the beams' elasticity (resistance to stretching). > 0.
    pub alpha: f64,
    /// β, the beams' rigidity (resistance to bending). > 0.
    pub beta: f64,
    /// T_f, the force cap in cells (Eq. 7). (0, 1].
    pub force_cap: f64,
    /// ε, the Snake stops when no node moves more than this many cells in a step. > 0.
    pub epsilon: f64,
    /// T_s, the most Snake steps. 0 disables the Snake (the centroids stay where they are).
    pub max_steps: usize,
    /// R: no node moves more than R times the largest force in one step. ≥ 1.
    pub step_ratio: f64,
    /// κ as a fraction of the mean displacement stiffness: the weak spring that makes K definite.
    pub spring: f64,
    /// Stop when the largest uncapped force has not fallen for 3 steps (§5, condition 2).
    pub stop_on_no_progress: bool,
    /// How forces become loads.
    pub load_model: LoadModel,
    /// Outline vertices kept per region by the simplification (N_boundary ≈ this × M). > 0.
    pub vertices_per_region: f64,
    /// Simplification tolerance in cells² (Visvalingam area); overrides `vertices_per_region`.
    pub simplify_tolerance: Option<f64>,
    /// Regions that touch at a single point count as adjacent.
    pub point_adjacency: bool,
    /// Lattice origin shifts (x right, y down) as fractions of a cell: one candidate each (§7).
    pub shifts: Vec<[f64; 2]>,
    /// Noise levels MD for the noisy candidates (§7); 0 is always run as well. Each ≥ 0.
    pub noise_levels: Vec<f64>,
    /// Seed of every random choice (noise and refinement).
    pub seed: u64,
    /// TOPSIS weights for C_location, C_adjacent, C_orientation, C_shape. Each ≥ 0, not all 0.
    pub topsis_weights: [f64; 4],
    /// The adjacency-aware refinement of §6b.
    pub refine: bool,
    /// Simulated-annealing moves of the refinement.
    pub refine_moves: usize,
    /// Starting temperature of the refinement (falls linearly to 0).
    pub refine_temperature: f64,
    /// Weight of an adjacent pair whose cells are not 8-neighbours.
    pub refine_w_adjacent: f64,
    /// Weight of the angle error of an adjacent pair, per 90°.
    pub refine_w_angle: f64,
    /// Weight of an adjacent pair misdirected by more than 45°.
    pub refine_w_misdirected: f64,
    /// Weight of a region's squared distance from its moved centroid, per cell².
    pub refine_w_location: f64,
    /// Free cells offered to the refinement, as a multiple of M (from the best by score).
    pub refine_cell_ratio: f64,
    /// Up to this many regions, the refinement only swaps cells, so the outline keeps its shape.
    pub refine_swap_only_below: usize,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            alpha: 1.0,
            beta: 1.0,
            force_cap: 0.1,
            epsilon: 1e-3,
            max_steps: 30,
            step_ratio: 5.0,
            spring: 1e-2,
            stop_on_no_progress: false,
            load_model: LoadModel::Nodal,
            vertices_per_region: 2.0,
            simplify_tolerance: None,
            point_adjacency: false,
            shifts: vec![[0.0, 0.0], [0.0, 0.5], [0.5, 0.0], [0.5, 0.5]],
            noise_levels: vec![0.02, 0.04],
            seed: 0,
            topsis_weights: [1.0; 4],
            refine: true,
            refine_moves: 40_000,
            refine_temperature: 0.5,
            refine_w_adjacent: 1.0,
            refine_w_angle: 1.0,
            refine_w_misdirected: 0.5,
            refine_w_location: 0.25,
            refine_cell_ratio: 1.3,
            refine_swap_only_below: 20,
        }
    }
}

impl Params {
    /// Checks every value against its documented range; the message names the parameter.
    pub fn validate(&self) -> Result<(), String> {
        fn positive(name: &str, v: f64) -> Result<(), String> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!(
                    "parameter {name} must be a finite number > 0, got {v}"
                ))
            }
        }
        fn non_negative(name: &str, v: f64) -> Result<(), String> {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(format!(
                    "parameter {name} must be a finite number >= 0, got {v}"
                ))
            }
        }
        positive("alpha", self.alpha)?;
        positive("beta", self.beta)?;
        positive("force_cap", self.force_cap)?;
        if self.force_cap > 1.0 {
            return Err(format!(
                "parameter force_cap must be at most 1 cell, got {}",
                self.force_cap
            ));
        }
        positive("epsilon", self.epsilon)?;
        positive("step_ratio", self.step_ratio)?;
        if self.step_ratio < 1.0 {
            return Err(format!(
                "parameter step_ratio must be >= 1, got {}",
                self.step_ratio
            ));
        }
        positive("spring", self.spring)?;
        positive("vertices_per_region", self.vertices_per_region)?;
        if let Some(t) = self.simplify_tolerance {
            non_negative("simplify_tolerance", t)?;
        }
        if self.shifts.is_empty() {
            return Err("parameter shifts must hold at least one shift".into());
        }
        for s in &self.shifts {
            for v in s {
                if !(v.is_finite() && (0.0..1.0).contains(v)) {
                    return Err(format!(
                        "parameter shifts: each shift must be in [0, 1), got {v}"
                    ));
                }
            }
        }
        for &n in &self.noise_levels {
            non_negative("noise_levels", n)?;
            if n > 1.0 {
                return Err(format!(
                    "parameter noise_levels: each level must be at most 1, got {n}"
                ));
            }
        }
        for &w in &self.topsis_weights {
            non_negative("topsis_weights", w)?;
        }
        if self.topsis_weights.iter().all(|&w| w == 0.0) {
            return Err("parameter topsis_weights must not all be 0".into());
        }
        non_negative("refine_temperature", self.refine_temperature)?;
        non_negative("refine_w_adjacent", self.refine_w_adjacent)?;
        non_negative("refine_w_angle", self.refine_w_angle)?;
        non_negative("refine_w_misdirected", self.refine_w_misdirected)?;
        non_negative("refine_w_location", self.refine_w_location)?;
        positive("refine_cell_ratio", self.refine_cell_ratio)?;
        if self.refine_cell_ratio < 1.0 {
            return Err(format!(
                "parameter refine_cell_ratio must be >= 1, got {}",
                self.refine_cell_ratio
            ));
        }
        Ok(())
    }
}

impl Params {
    /// The names `set` accepts, alphabetically.
    pub fn names() -> Vec<String> {
        match serde_json::to_value(Params::default()) {
            Ok(serde_json::Value::Object(fields)) => fields.keys().cloned().collect(),
            _ => Vec::new(),
        }
    }

    /// Sets one parameter by name from text, as the command line and the C API receive it:
    /// numbers, `true`/`false`, `element`/`nodal`, comma-separated lists (`0.02,0.04`), shifts as
    /// `x:y` pairs (`0:0,0.5:0.5`), and `none` to clear the simplification tolerance. The new
    /// value is range-checked; on error nothing changes and the message names the parameter.
    pub fn set(&mut self, name: &str, value: &str) -> Result<(), String> {
        use serde_json::Value;
        let mut all = serde_json::to_value(&*self).map_err(|e| e.to_string())?;
        let fields = all.as_object_mut().ok_or("parameters are not an object")?;
        let current = fields
            .get(name)
            .ok_or_else(|| format!("unknown parameter {name:?}"))?;
        let bad = |what: &str| format!("parameter {name}: {what}, got {value:?}");
        let number = |text: &str| -> Result<Value, String> {
            let v: f64 = text.trim().parse().map_err(|_| bad("expected a number"))?;
            serde_json::Number::from_f64(v)
                .map(Value::Number)
                .ok_or_else(|| bad("expected a finite number"))
        };
        let text = value.trim();
        let parsed = match current {
            // Only an optional parameter takes it; any other refuses it when read back below.
            _ if text.eq_ignore_ascii_case("none") => Value::Null,
            Value::Bool(_) => Value::Bool(match text.to_ascii_lowercase().as_str() {
                "true" | "yes" | "on" | "1" => true,
                "false" | "no" | "off" | "0" => false,
                _ => return Err(bad("expected true or false")),
            }),
            Value::String(_) => Value::String(text.to_ascii_lowercase()),
            Value::Number(n) if n.is_u64() => Value::from(
                text.parse::<u64>()
                    .map_err(|_| bad("expected a whole number >= 0"))?,
            ),
            Value::Number(_) | Value::Null => number(text)?,
            Value::Array(items)
                if matches!(items.first(), Some(Value::Array(_))) || name == "shifts" =>
            {
                let pairs = text.split(',').map(|pair| {
                    let (x, y) = pair
                        .split_once(':')
                        .ok_or_else(|| bad("expected x:y pairs"))?;
                    Ok(Value::Array(vec![number(x)?, number(y)?]))
                });
                Value::Array(pairs.collect::<Result<_, String>>()?)
            }
            Value::Array(_) if text.is_empty() => Value::Array(Vec::new()),
            Value::Array(_) => Value::Array(text.split(',').map(number).collect::<Result<_, _>>()?),
            Value::Object(_) => return Err(bad("cannot be set from text")),
        };
        fields.insert(name.to_owned(), parsed);
        let candidate: Params = serde_json::from_value(all).map_err(|e| bad(&e.to_string()))?;
        candidate.validate()?;
        *self = candidate;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        Params::default().validate().unwrap();
    }

    #[test]
    fn set_parses_every_kind_of_value() {
        let mut p = Params::default();
        p.set("alpha", "2.5").unwrap();
        p.set("max_steps", "12").unwrap();
        p.set("refine", "no").unwrap();
        p.set("load_model", "Element").unwrap();
        p.set("noise_levels", "0.01, 0.03").unwrap();
        p.set("shifts", "0:0,0.25:0.75").unwrap();
        p.set("simplify_tolerance", "0.2").unwrap();
        assert_eq!(p.alpha, 2.5);
        assert_eq!(p.max_steps, 12);
        assert!(!p.refine);
        assert_eq!(p.load_model, LoadModel::Element);
        assert_eq!(p.noise_levels, vec![0.01, 0.03]);
        assert_eq!(p.shifts, vec![[0.0, 0.0], [0.25, 0.75]]);
        assert_eq!(p.simplify_tolerance, Some(0.2));
        p.set("simplify_tolerance", "none").unwrap();
        assert_eq!(p.simplify_tolerance, None);
    }

    #[test]
    fn set_refuses_unknown_names_and_bad_values_and_keeps_the_old_value() {
        let mut p = Params::default();
        let err = p.set("gamma", "1").unwrap_err();
        assert!(err.contains("unknown parameter \"gamma\""), "{err}");
        let err = p.set("alpha", "-1").unwrap_err();
        assert!(err.contains("alpha"), "{err}");
        let err = p.set("max_steps", "1.5").unwrap_err();
        assert!(err.contains("max_steps"), "{err}");
        let err = p.set("load_model", "springs").unwrap_err();
        assert!(err.contains("load_model"), "{err}");
        let err = p.set("shifts", "0.5").unwrap_err();
        assert!(err.contains("x:y"), "{err}");
        assert_eq!(p, Params::default());
    }

    #[test]
    fn names_lists_every_field() {
        let names = Params::names();
        assert!(names.iter().any(|n| n == "alpha"));
        assert!(names.iter().any(|n| n == "refine_swap_only_below"));
        for n in &names {
            let err = Params::default().set(n, "x").unwrap_err();
            assert!(err.contains(n.as_str()), "{err}");
        }
    }
}
