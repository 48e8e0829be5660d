//! Minimum-cost 2-D assignment of rows to columns (`rows ≤ columns`), the shortest
//! augmenting path method (Jonker–Volgenant style, as described by Crouse, "On implementing
//! 2D rectangular assignment algorithms", IEEE TAES 2016), the method behind SciPy's
//! `linear_sum_assignment`, which Stone Soup's GNN associator calls.
//!
//! Rows are assigned one after another. For row `r`, a Dijkstra search over reduced costs
//! `c_ij − u_i − v_j` (dual variables `u`, `v`) grows a tree of rows from `r` until it
//! reaches an unassigned column (the sink); the path is then flipped and the duals updated.
//! Ties choose, among the columns of equal path cost, the one scanned first, except that an
//! unassigned column beats an assigned one; columns are scanned in the order of a list
//! that starts descending and from which the chosen column is swapped out with the last.
//! This is the order SciPy scans them in, so ties go the same way for the same costs.
//!
//! `+∞` marks a forbidden pair; NaN or `−∞` is an error, as is a row that can reach no
//! column.

use crate::error::{ModelError, Result};

/// The column assigned to each row of the row-major `rows × cols` matrix `cost`
/// minimising the total cost.
pub fn assign(cost: &[f64], rows: usize, cols: usize) -> Result<Vec<usize>> {
    if rows > cols {
        return Err(ModelError::shape(
            "cost",
            format!("must have at least as many columns as rows, got ({rows}, {cols})"),
        ));
    }
    if cost.len() != rows * cols {
        return Err(ModelError::shape(
            "cost",
            format!("must be ({rows}, {cols}), got {} values", cost.len()),
        ));
    }
    if cost.iter().any(|c| c.is_nan() || *c == f64::NEG_INFINITY) {
        return Err(ModelError::invalid("cost", "contains NaN or -inf"));
    }
    let mut u = vec![0.0; rows];
    let mut v = vec![0.0; cols];
    let mut path_cost = vec![f64::INFINITY; cols];
    let mut path = vec![usize::MAX; cols];
    let mut col4row = vec![usize::MAX; rows];
    let mut row4col = vec![usize::MAX; cols];
    let mut seen_row = vec![false; rows];
    let mut seen_col = vec![false; cols];
    let mut remaining = vec![0usize; cols];
    for current in 0..rows {
        // the shortest augmenting path from `current` to an unassigned column
        for (k, slot) in remaining.iter_mut().enumerate() {
            *slot = cols - k - 1;
        }
        let mut left = cols;
        seen_row.fill(false);
        seen_col.fill(false);
        path_cost.fill(f64::INFINITY);
        let mut reached = 0.0;
        let mut i = current;
        let sink = loop {
            seen_row[i] = true;
            let mut lowest = f64::INFINITY;
            let mut chosen = usize::MAX;
            for (k, &j) in remaining[..left].iter().enumerate() {
                let reduced = reached + cost[i * cols + j] - u[i] - v[j];
                if reduced < path_cost[j] {
                    path[j] = i;
                    path_cost[j] = reduced;
                }
                if path_cost[j] < lowest || (path_cost[j] == lowest && row4col[j] == usize::MAX) {
                    lowest = path_cost[j];
                    chosen = k;
                }
            }
            reached = lowest;
            if reached == f64::INFINITY || chosen == usize::MAX {
                return Err(ModelError::infeasible(
                    "cost",
                    format!("row {current} can reach no column: the assignment is not feasible"),
                ));
            }
            let j = remaining[chosen];
            seen_col[j] = true;
            left -= 1;
            remaining[chosen] = remaining[left];
            if row4col[j] == usize::MAX {
                break j;
            }
            i = row4col[j];
        };
        // dual updates, then the path flipped
        u[current] += reached;
        for r in 0..rows {
            if seen_row[r] && r != current {
                u[r] += reached - path_cost[col4row[r]];
            }
        }
        for j in 0..cols {
            if seen_col[j] {
                v[j] -= reached - path_cost[j];
            }
        }
        let mut j = sink;
        loop {
            let r = path[j];
            row4col[j] = r;
            std::mem::swap(&mut col4row[r], &mut j);
            if r == current {
                break;
            }
        }
    }
    Ok(col4row)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(cost: &[f64], rows: usize, cols: usize) -> f64 {
        fn visit(cost: &[f64], rows: usize, cols: usize, r: usize, used: &mut Vec<bool>) -> f64 {
            if r == rows {
                return 0.0;
            }
            let mut best = f64::INFINITY;
            for j in 0..cols {
                if !used[j] && cost[r * cols + j].is_finite() {
                    used[j] = true;
                    best = best.min(cost[r * cols + j] + visit(cost, rows, cols, r + 1, used));
                    used[j] = false;
                }
            }
            best
        }
        visit(cost, rows, cols, 0, &mut vec![false; cols])
    }

    #[test]
    fn finds_the_minimum_of_random_problems() {
        let mut state = 99u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64) / ((1u64 << 53) as f64)
        };
        for trial in 0..200 {
            let rows = 1 + trial % 4;
            let cols = rows + trial % 3;
            let cost: Vec<f64> = (0..rows * cols)
                .map(|_| {
                    if next() < 0.3 {
                        f64::INFINITY
                    } else {
                        (next() * 5.0).floor()
                    }
                })
                .collect();
            let best = brute(&cost, rows, cols);
            match assign(&cost, rows, cols) {
                Ok(col4row) => {
                    let total: f64 = col4row.iter().enumerate().map(|(r, &j)| cost[r * cols + j]).sum();
                    assert_eq!(total, best, "trial {trial}");
                    let mut used = col4row.clone();
                    used.sort();
                    used.dedup();
                    assert_eq!(used.len(), rows);
                }
                Err(_) => assert_eq!(best, f64::INFINITY, "trial {trial}"),
            }
        }
    }

    #[test]
    fn ties_go_as_scipys() {
        // (checked against scipy.optimize.linear_sum_assignment)
        assert_eq!(assign(&[1.0, 1.0, 1.0, 1.0], 2, 2).unwrap(), vec![0, 1]);
        assert_eq!(assign(&[0.0, 0.0, 0.0], 1, 3).unwrap(), vec![0]);
        let inf = f64::INFINITY;
        assert_eq!(
            assign(&[2.0, 2.0, 3.0, inf, 2.0, 2.0, inf, 3.0], 2, 4).unwrap(),
            vec![0, 1]
        );
    }

    #[test]
    fn bad_inputs_are_errors() {
        assert!(assign(&[f64::NAN], 1, 1).is_err());
        assert!(assign(&[f64::NEG_INFINITY], 1, 1).is_err());
        assert!(assign(&[f64::INFINITY], 1, 1).is_err());
        assert!(assign(&[1.0, 2.0], 2, 1).is_err());
        assert!(assign(&[1.0], 1, 2).is_err());
        assert_eq!(assign(&[], 0, 3).unwrap(), Vec::<usize>::new());
    }
}
