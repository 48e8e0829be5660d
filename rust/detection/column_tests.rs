//! P_D over (D, N) particle arrays, C- and F-ordered, against the (N, D) row path on the
//! transposed array.

use super::*;
use crate::distinct::ln_in_place;
use crate::fuzz::{detection_factor, mapping, mapping_of, pose, states};
use crate::land::Polygon;
use proptest::prelude::*;
use std::f64::consts::PI;

fn bands(edges: &[f64], values: &[f64]) -> DetectionFactor {
    DetectionFactor::Range(RangeBands::new(edges.to_vec(), values.to_vec(), vec![true; edges.len()]).unwrap())
}

/// The paper's radar; an island with line of sight (P_D 0 on and behind it); many bands
/// (the square-root band path); a constant.
fn models() -> Vec<DetectionModel> {
    let island = Arc::new(
        LandMask::new(vec![Polygon {
            shell: vec![[300.0, -200.0], [600.0, -200.0], [600.0, 200.0], [300.0, 200.0]],
            holes: vec![],
        }])
        .unwrap(),
    );
    vec![
        DetectionModel::new(vec![
            bands(&[50.0, 1612.0], &[0.0, 0.4, 0.0]),
            DetectionFactor::Sector(AngularSector::new(PI, 1.1, 0.0, 1.0).unwrap()),
        ])
        .unwrap(),
        DetectionModel::new(vec![
            DetectionFactor::Constant(0.9),
            DetectionFactor::Land(island.clone()),
            DetectionFactor::Sight(Arc::new(LineOfSight::new(island).unwrap())),
        ])
        .unwrap(),
        DetectionModel::new(vec![bands(
            &[100.0, 200.0, 300.0, 400.0, 500.0, 600.0],
            &[0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.0],
        )])
        .unwrap(),
        DetectionModel::new(vec![DetectionFactor::Constant(0.917)]).unwrap(),
    ]
}

/// (D, N) columns and the same states as (N, D) rows.
fn particles(n: usize, ndim: usize) -> (Vec<f64>, Vec<f64>) {
    // splitmix64 → uniform in [-1200, 1200): rows independent of each other.
    let columns: Vec<f64> = (0..(ndim * n) as u64)
        .map(|k| {
            let mut z = (k + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15);
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64 * 2400.0 - 1200.0
        })
        .collect();
    let mut rows = vec![0.0; ndim * n];
    for j in 0..ndim {
        for i in 0..n {
            rows[i * ndim + j] = columns[j * n + i];
        }
    }
    (columns, rows)
}

#[test]
fn columns_give_the_row_bits() {
    // One chunk, a ragged last chunk, and enough particles for the parallel split.
    for n in [1, 1500, 70_001] {
        for (ndim, mapping) in [
            (4, PositionMapping::default()),
            (6, PositionMapping::new(4, 1).unwrap()),
        ] {
            let (columns, rows) = particles(n, ndim);
            for (m, model) in models().iter().enumerate() {
                let scan = model.at_pose(&Pose::new(-20.0, 15.0, 0.4).unwrap());
                let (mut by_column, mut by_row, mut fortran) = (vec![9.0; n], vec![7.0; n], vec![5.0; n]);
                scan.at_particles(&columns, ndim, MemoryOrder::C, mapping, &mut by_column)
                    .unwrap();
                scan.at_states(&rows, ndim, mapping, &mut by_row).unwrap();
                // An F-ordered (D, N) array is the row array's memory.
                scan.at_particles(&rows, ndim, MemoryOrder::F, mapping, &mut fortran)
                    .unwrap();
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&by_column), bits(&by_row), "model {m}, n {n}, ndim {ndim}");
                assert_eq!(bits(&fortran), bits(&by_row), "model {m}, n {n}, ndim {ndim}");
                if n > 1000 && m < 3 {
                    assert!(
                        by_column.contains(&0.0) && by_column.iter().any(|&p| p > 0.0),
                        "model {m}, n {n}, ndim {ndim}: P_D 0 and > 0 regions"
                    );
                }
            }
        }
    }
}

#[test]
fn log_of_columns_is_ln_with_minus_infinity_where_pd_is_zero() {
    let (columns, _) = particles(5000, 4);
    let radar = models().swap_remove(0);
    let scan = radar.at_pose(&Pose::new(0.0, 0.0, 0.0).unwrap());
    let mut pd = vec![0.0; 5000];
    scan.at_particles(&columns, 4, MemoryOrder::C, PositionMapping::default(), &mut pd)
        .unwrap();
    let mut log_pd = pd.clone();
    ln_in_place(&mut log_pd);
    for (p, l) in pd.iter().zip(&log_pd) {
        assert_eq!(l.to_bits(), p.ln().to_bits());
    }
    assert!(log_pd.contains(&f64::NEG_INFINITY) && log_pd.contains(&0.4f64.ln()));
}

#[test]
fn column_errors_name_particles() {
    let radar = models().swap_remove(0);
    let scan = radar.at_pose(&Pose::new(0.0, 0.0, 0.0).unwrap());
    let n = 70_000;
    let (mut columns, _) = particles(n, 4);
    columns[2 * n + 50_001] = f64::NAN; // y of particle 50 001
    columns[60_000] = f64::INFINITY; // x of particle 60 000
    let mut out = vec![0.0; n];
    let err = scan
        .at_particles(&columns, 4, MemoryOrder::C, PositionMapping::default(), &mut out)
        .unwrap_err();
    assert_eq!(
        err,
        ModelError::invalid(
            "particles",
            "particle 50001 (column 50001) has a NaN or infinite position"
        )
    );
    let (_, mut rows) = particles(n, 4);
    rows[40_000 * 4] = f64::NAN;
    let err = scan
        .at_particles(&rows, 4, MemoryOrder::F, PositionMapping::default(), &mut out)
        .unwrap_err();
    assert_eq!(
        err,
        ModelError::invalid(
            "particles",
            "particle 40000 (column 40000) has a NaN or infinite position"
        )
    );
    // A NaN velocity is not read: no error.
    let (mut columns, _) = particles(10, 4);
    columns[3 * 10 + 4] = f64::NAN;
    scan.at_particles(&columns, 4, MemoryOrder::C, PositionMapping::default(), &mut [0.0; 10])
        .unwrap();
    // Too few rows for the mapping, or a length that is not ndim × N.
    let err = scan
        .at_particles(
            &columns[..20],
            2,
            MemoryOrder::C,
            PositionMapping::default(),
            &mut [0.0; 10],
        )
        .unwrap_err();
    assert_eq!(err.argument(), "particles");
    assert!(err.to_string().contains("2 rows"), "{err}");
    let err = scan
        .at_particles(&columns, 4, MemoryOrder::F, PositionMapping::default(), &mut [0.0; 9])
        .unwrap_err();
    assert_eq!(err.argument(), "particles");
}

proptest! {
    /// Hostile models, poses, mappings and arrays (NaN, ±inf, ragged lengths, zero rows):
    /// the particle path never panics, fails exactly where the row path on the same states
    /// fails, and otherwise gives its bits, in either memory order; its log through the
    /// table is the per-element `ln`.
    #[test]
    fn particles_never_panic_and_agree_with_rows(
        factors in prop::collection::vec(detection_factor(), 0..5),
        p in pose(),
        (rows, ncols, n) in states(),
        m in mapping(),
        fortran in any::<bool>(),
    ) {
        let factors: Vec<DetectionFactor> = factors.into_iter().flatten().collect();
        let Ok(model) = DetectionModel::new(factors) else { return Ok(()); };
        let Ok(pose) = Pose::raised(p.0, p.1, p.2, 12.5) else { return Ok(()); };
        let Some(mapping) = mapping_of(m) else { return Ok(()); };
        let scan = model.at_pose(&pose);
        let mut by_rows = vec![-7.0; n];
        let row_result = scan.at_states(&rows, ncols, mapping, &mut by_rows);
        // F order is the rows' memory; C order their transpose (when they are a block).
        let (particles, order) = if fortran || rows.len() != n * ncols {
            (rows.clone(), MemoryOrder::F)
        } else {
            ((0..ncols * n).map(|k| rows[(k % n) * ncols + k / n]).collect(), MemoryOrder::C)
        };
        let mut by_particles = vec![-5.0; n];
        let result = scan.at_particles(&particles, ncols, order, mapping, &mut by_particles);
        prop_assert_eq!(result.is_ok(), row_result.is_ok(), "{:?} vs {:?}", result, row_result);
        if let Err(err) = result {
            // (a horizon at the target's height read without heights: the mapping's fault)
            let row_argument = row_result.unwrap_err().argument().to_string();
            let expected = if row_argument == "position_mapping" { "position_mapping" } else { "particles" };
            prop_assert_eq!(err.argument(), expected);
            return Ok(());
        }
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        prop_assert_eq!(bits(&by_particles), bits(&by_rows));
        let mut logs = by_particles.clone();
        ln_in_place(&mut logs);
        prop_assert_eq!(bits(&logs), by_particles.iter().map(|p| p.ln().to_bits()).collect::<Vec<_>>());
    }
}
