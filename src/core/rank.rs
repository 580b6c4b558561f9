//! TOPSIS ranking of candidate layouts (method.md §7).

use super::LayoutMetrics;

/// Closeness of each candidate to the ideal (0..=1, higher is better), with vector
/// normalisation; weights for C_location, C_adjacent, C_orientation, C_shape.
///
/// For criterion j with column x_·j: r_ij = x_ij / sqrt(Σ_i x_ij²), v_ij = w_j · r_ij; the ideal
/// takes the best v of each column (lowest for the costs C_location and C_orientation, highest
/// for the benefits C_adjacent and C_shape) and the anti-ideal the worst; with d⁺ and d⁻ the
/// Euclidean distances to them, the closeness is d⁻ / (d⁺ + d⁻).
///
/// A column that is all zero cannot be normalised and contributes nothing. When d⁺ + d⁻ = 0 no
/// weighted criterion tells the candidates apart (they are all identical, or there is one), and
/// every closeness is 1.0, never NaN. Weights are non-negative (as `Params` validates) and only
/// their ratios matter; the metrics are expected to be finite.
pub fn topsis(candidates: &[LayoutMetrics], weights: [f64; 4]) -> Vec<f64> {
    let rows: Vec<[f64; 4]> = candidates.iter().map(criteria).collect();
    let mut weighted = rows.clone();
    let mut ideal = [0.0; 4];
    let mut anti_ideal = [0.0; 4];
    for (j, (&weight, &benefit)) in weights.iter().zip(&BENEFIT).enumerate() {
        let norm = rows.iter().map(|r| r[j] * r[j]).sum::<f64>().sqrt();
        let column = weighted.iter_mut().map(|r| &mut r[j]);
        if norm > 0.0 {
            column.for_each(|v| *v *= weight / norm);
        } else {
            column.for_each(|v| *v = 0.0);
        }
        let (low, high) = weighted
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
                (lo.min(r[j]), hi.max(r[j]))
            });
        (ideal[j], anti_ideal[j]) = if benefit { (high, low) } else { (low, high) };
    }
    weighted
        .iter()
        .map(|v| {
            let to_ideal = euclidean(v, &ideal);
            let to_anti_ideal = euclidean(v, &anti_ideal);
            let spread = to_ideal + to_anti_ideal;
            if spread > 0.0 {
                to_anti_ideal / spread
            } else {
                1.0
            }
        })
        .collect()
}

/// Whether more is better, per criterion in the order of [`criteria`].
const BENEFIT: [bool; 4] = [false, true, false, true];

/// The four ranked criteria of a candidate, in the order of the weights.
fn criteria(m: &LayoutMetrics) -> [f64; 4] {
    [m.location, m.adjacent, m.orientation, m.shape]
}

fn euclidean(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn metrics(location: f64, adjacent: f64, orientation: f64, shape: f64) -> LayoutMetrics {
        LayoutMetrics {
            location,
            adjacent,
            orientation,
            shape,
            ..LayoutMetrics::default()
        }
    }

    fn best(scores: &[f64]) -> usize {
        (0..scores.len())
            .max_by(|&a, &b| scores[a].total_cmp(&scores[b]))
            .unwrap()
    }

    #[test]
    fn a_dominating_candidate_ranks_first_with_closeness_one() {
        let candidates = [
            metrics(0.9, 0.80, 25.0, 0.85),
            metrics(0.7, 0.90, 18.0, 0.92),
            metrics(1.1, 0.75, 30.0, 0.80),
        ];
        let scores = topsis(&candidates, [1.0; 4]);
        assert_eq!(best(&scores), 1);
        // It is the ideal itself, and the third is the anti-ideal.
        assert!((scores[1] - 1.0).abs() < 1e-12, "{scores:?}");
        assert!(scores[2].abs() < 1e-12, "{scores:?}");
        assert!(scores[0] > 0.0 && scores[0] < 1.0);
    }

    #[test]
    fn weights_change_the_order() {
        // The first keeps adjacency better, the second orientation.
        let candidates = [metrics(1.0, 0.95, 30.0, 0.9), metrics(1.0, 0.80, 15.0, 0.9)];
        let adjacency_heavy = topsis(&candidates, [1.0, 10.0, 1.0, 1.0]);
        let orientation_heavy = topsis(&candidates, [1.0, 1.0, 10.0, 1.0]);
        assert_eq!(best(&adjacency_heavy), 0, "{adjacency_heavy:?}");
        assert_eq!(best(&orientation_heavy), 1, "{orientation_heavy:?}");
    }

    #[test]
    fn only_weight_ratios_matter() {
        let candidates = [
            metrics(1.0, 0.95, 30.0, 0.9),
            metrics(0.8, 0.80, 15.0, 0.7),
            metrics(1.2, 0.85, 20.0, 0.8),
        ];
        let a = topsis(&candidates, [1.0, 2.0, 3.0, 4.0]);
        let b = topsis(&candidates, [0.5, 1.0, 1.5, 2.0]);
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-12);
        }
    }

    #[test]
    fn identical_candidates_all_get_one() {
        let m = metrics(0.8, 0.9, 20.0, 0.85);
        assert_eq!(topsis(&[m, m, m], [1.0; 4]), vec![1.0; 3]);
        assert_eq!(topsis(&[m], [1.0; 4]), vec![1.0]);
        assert_eq!(topsis(&[], [1.0; 4]), Vec::<f64>::new());
    }

    #[test]
    fn zero_columns_and_zero_weights_give_no_nan() {
        // Location and orientation are 0 everywhere (a perfect fit): those columns drop out and
        // the ranking follows adjacency and shape.
        let candidates = [metrics(0.0, 0.9, 0.0, 0.8), metrics(0.0, 0.7, 0.0, 0.6)];
        let scores = topsis(&candidates, [1.0; 4]);
        assert!(scores.iter().all(|s| s.is_finite()), "{scores:?}");
        assert_eq!(scores, vec![1.0, 0.0]);
        // Only a weight on a criterion where they tie: nothing separates them.
        let tied = topsis(&candidates, [1.0, 0.0, 0.0, 0.0]);
        assert_eq!(tied, vec![1.0, 1.0]);
    }
}
