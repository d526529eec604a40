//! The two small formulas of the report: the Pareto front of the trade plot and DESIGN.md's
//! speedup model.

/// Indices of the points no other point beats on both axes (both minimized), in order of
/// increasing `x`. A point is dominated when another is at most as large on both axes and smaller
/// on one; of identical points only the first is kept. Points with a NaN coordinate never make the
/// front.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> =
        (0..points.len()).filter(|&i| !points[i].0.is_nan() && !points[i].1.is_nan()).collect();
    // by x, then y: a sweep keeps every point lower than all before it
    order.sort_by(|&a, &b| points[a].0.total_cmp(&points[b].0).then(points[a].1.total_cmp(&points[b].1)));
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in order {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

/// The speedup over depth peeling that DESIGN.md's model predicts: `K = N·Tv / (Tv + Tf)`, for a
/// scene `n` layers deep, a plain geometry pass of `tv` and a technique whose extra fragment cost
/// over that pass is `tf` (depth peeling spends about N plain passes; the technique one pass plus
/// its extra cost).
pub fn predicted_speedup(n: f64, tv: f64, tf: f64) -> f64 {
    n * tv / (tv + tf)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn front_keeps_only_undominated_points() {
        let points = [
            (1.0, 0.5),      // 0: fastest
            (2.0, 0.5),      // 1: dominated by 0 (slower, same error)
            (3.0, 0.0),      // 2: exact
            (2.5, 0.1),      // 3: between
            (4.0, 0.0),      // 4: dominated by 2
            (1.0, 0.5),      // 5: a copy of 0
            (0.5, f64::NAN), // 6: not a point
            (2.5, 0.2),      // 7: dominated by 3
        ];
        assert_eq!(pareto_front(&points), vec![0, 3, 2]);
        assert!(pareto_front(&[]).is_empty());
        assert_eq!(pareto_front(&[(1.0, 1.0)]), vec![0]);
    }

    #[test]
    fn model_formula() {
        // no extra cost: the technique is one plain pass, N times faster than N passes
        assert_eq!(predicted_speedup(8.0, 2.0, 0.0), 8.0);
        // extra cost equal to a pass halves it
        assert_eq!(predicted_speedup(8.0, 2.0, 2.0), 4.0);
        // a technique slower than N passes predicts a slowdown
        assert!(predicted_speedup(2.0, 1.0, 3.0) < 1.0);
    }
}
