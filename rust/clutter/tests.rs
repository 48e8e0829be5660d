//! Unit tests of the clutter model: the paper's rules, measured ranges, learned maps, backends, errors.

use super::*;
use crate::elevation::ElevationSector;

#[test]
fn a_metadata_column_beyond_usize_is_an_error_not_an_overflow() {
    let rule = MetadataThreshold {
        column: usize::MAX,
        threshold: 10.0,
        below: 1e-1,
        at_or_above: 1e-3,
        missing: None,
    };
    assert!(ClutterModel::new(vec![ClutterFactor::Metadata(rule)]).is_err());
}

#[test]
fn measured_ranges_take_the_place_of_the_position_range() {
    let bands = RangeBands::new(vec![1000.0], vec![1e-3, 1e-2], vec![true]).unwrap();
    let model = ClutterModel::new(vec![ClutterFactor::Range(bands)]).unwrap();
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    // positions an ulp short of the edge; the measured range is exactly on it
    let short = 1000.0f64.next_down();
    let positions = [short, 0.0, short, 0.0, short, 0.0];
    let mut out = [0.0; 3];
    model
        .evaluate_with_ranges(&pose, &positions, &[], Some(&[1000.0, f64::NAN, 999.0]), &mut out)
        .unwrap();
    assert_eq!(out, [1e-2, 1e-3, 1e-3]);
    let err = model
        .evaluate_with_ranges(&pose, &positions, &[], Some(&[f64::INFINITY, 0.0, 0.0]), &mut out)
        .unwrap_err();
    assert_eq!(
        err,
        ModelError::non_finite("ranges", 0, "range is infinite or negative (NaN = use the position)")
    );
    // a negative measured range is no range: refused, naming its row
    let err = model
        .evaluate_with_ranges(&pose, &positions, &[], Some(&[0.0, -1.0, f64::NAN]), &mut out)
        .unwrap_err();
    assert_eq!(
        err,
        ModelError::non_finite("ranges", 1, "range is infinite or negative (NaN = use the position)")
    );
    assert!(model
        .evaluate_with_ranges(&pose, &positions, &[], Some(&[1.0]), &mut out)
        .is_err());
}

#[test]
fn paper_lidar_area_rule() {
    let model = ClutterModel::new(vec![ClutterFactor::Metadata(MetadataThreshold {
        column: 0,
        threshold: 10.0,
        below: 1e-1,
        at_or_above: 1e-3,
        missing: None,
    })])
    .unwrap();
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    let mut out = [0.0; 3];
    model
        .evaluate(&pose, &[0.0; 6], &[9.99, 10.0, 250.0], &mut out)
        .unwrap();
    assert_eq!(out, [1e-1, 1e-3, 1e-3]);
    let err = model
        .evaluate(&pose, &[0.0; 6], &[9.99, f64::NAN, 250.0], &mut out)
        .unwrap_err();
    assert_eq!(
        err,
        ModelError::non_finite(
            "metadata",
            1,
            "metadata column 0 is missing and the rule has no `missing` value"
        )
    );
}

#[test]
fn infinite_metadata_is_an_error_naming_metadata() {
    let rule = MetadataThreshold {
        column: 0,
        threshold: 10.0,
        below: 1e-1,
        at_or_above: 1e-3,
        missing: Some(1.0),
    };
    let model = ClutterModel::new(vec![ClutterFactor::Metadata(rule)]).unwrap();
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    let mut out = [0.0; 3];
    for bad in [f64::INFINITY, f64::NEG_INFINITY] {
        let err = model
            .evaluate(&pose, &[0.0; 6], &[1.0, f64::NAN, bad], &mut out)
            .unwrap_err();
        assert_eq!(
            err,
            ModelError::non_finite(
                "metadata",
                2,
                format!("metadata column 0 is {bad}; values must be finite (NaN = missing)")
            )
        );
    }
}

#[test]
fn paper_radar_range_rule() {
    let model = ClutterModel::new(vec![ClutterFactor::Range(
        RangeBands::new(vec![1000.0], vec![1e-3, 1e-2], vec![true]).unwrap(),
    )])
    .unwrap();
    let pose = Pose::new(10.0, 10.0, 0.0).unwrap();
    let mut out = [0.0; 3];
    model
        .evaluate(&pose, &[10.0, 1009.0, 10.0, 1010.0, 1010.0, 10.0], &[], &mut out)
        .unwrap();
    assert_eq!(out, [1e-3, 1e-2, 1e-2]);
}

#[test]
fn zero_or_negative_density_is_rejected() {
    assert!(ClutterModel::new(vec![ClutterFactor::Constant(0.0)]).is_err());
    assert!(ClutterModel::new(vec![ClutterFactor::Constant(-1e-3)]).is_err());
}

fn learned_map() -> ClutterFactor {
    use crate::clutter_map::MapSpace;
    let bearings: Vec<f64> = (0..=12)
        .map(|i| -std::f64::consts::PI + i as f64 * std::f64::consts::PI / 6.0)
        .collect();
    let mut map = ClutterMap::new(
        MapSpace::BearingRange,
        [bearings, vec![0.0, 300.0, 1000.0, 1600.0]],
        1e-3,
        3.0,
        0.95,
    )
    .unwrap();
    let pose = Pose::new(3.0, -4.0, 0.7).unwrap();
    let clutter: Vec<f64> = (0..80)
        .map(|k| ((k as f64) * 1.618_033_988_749_895).sin() * 1500.0)
        .collect();
    for scan in 0..5 {
        map.update(
            &pose,
            &clutter[8 * scan..8 * scan + 16],
            None,
            &[clutter[scan], clutter[scan + 1], 150.0],
        )
        .unwrap();
    }
    ClutterFactor::Map(Arc::new(RwLock::new(map)))
}

#[test]
fn a_model_reads_its_map_as_it_stands() {
    let factor = learned_map();
    let ClutterFactor::Map(shared) = &factor else {
        unreachable!()
    };
    let model = ClutterModel::new(vec![ClutterFactor::Constant(2.0), factor.clone()]).unwrap();
    assert!(model.uses_position());
    let pose = Pose::new(3.0, -4.0, 0.7).unwrap();
    let at = [500.0, 300.0];
    let mut before = [0.0];
    model.evaluate(&pose, &at, &[], &mut before).unwrap();
    assert_eq!(
        before[0],
        2.0 * read_map(shared).value_at(&pose, at[0], at[1], f64::NAN)
    );
    shared
        .write()
        .unwrap()
        .update(&pose, &[at, at, at].concat(), None, &[])
        .unwrap();
    let mut after = [0.0];
    model.evaluate(&pose, &at, &[], &mut after).unwrap();
    assert!(after[0] > before[0]);
    assert_eq!(after[0], 2.0 * read_map(shared).value_at(&pose, at[0], at[1], f64::NAN));
    // equal models share the map itself
    assert_eq!(
        model,
        ClutterModel::new(vec![ClutterFactor::Constant(2.0), factor]).unwrap()
    );
    assert_ne!(
        model,
        ClutterModel::new(vec![ClutterFactor::Constant(2.0), learned_map()]).unwrap()
    );
}

#[test]
fn every_backend_gives_the_reference_bits() {
    use crate::simd::{run_on, Backend};
    let bands = |edges: Vec<f64>, values: Vec<f64>, owns: Vec<bool>| {
        ClutterFactor::Range(RangeBands::new(edges, values, owns).unwrap())
    };
    let rule = |column, threshold, missing| {
        ClutterFactor::Metadata(MetadataThreshold {
            column,
            threshold,
            below: 1e-1,
            at_or_above: 1e-3,
            missing,
        })
    };
    // Each pass order of the kernel: a constant first, a range factor first (its pass
    // also starts λ), a metadata rule first with range bands later, no factors, no
    // position at all.
    let models = [
        vec![
            ClutterFactor::Constant(0.7),
            bands(vec![100.0, 1000.0], vec![1e-3, 1e-2, 3e-2], vec![true, false]),
            rule(1, 10.0, Some(1e-2)),
            rule(0, 0.5, None),
        ],
        vec![
            bands(vec![1000.0], vec![1e-3, 1e-2], vec![true]),
            rule(0, 10.0, Some(1e-2)),
        ],
        vec![
            rule(0, 10.0, Some(1e-2)),
            bands(vec![100.0], vec![2.0, 3.0], vec![false]),
            ClutterFactor::Constant(1e-300),
            ClutterFactor::Constant(1e-300),
        ],
        vec![],
        vec![ClutterFactor::Constant(0.25), rule(2, 5.0, Some(4.0))],
        // a learned map with some evidence, between a range factor and a rule
        vec![
            bands(vec![1000.0], vec![1e-3, 1e-2], vec![true]),
            learned_map(),
            rule(0, 10.0, Some(1e-2)),
        ],
        vec![learned_map()],
        // detections with a height: an elevation sector first (it reads heights), and after
        // slant-range bands
        vec![
            ClutterFactor::Elevation(ElevationSector::new(-0.1, 0.05, 8.0, 1e-4).unwrap()),
            bands(vec![1000.0], vec![1e-3, 1e-2], vec![true]),
        ],
        vec![
            bands(vec![500.0, 1000.0], vec![1e-3, 1e-2, 3e-2], vec![true, false]),
            ClutterFactor::Elevation(ElevationSector::new(0.0, 1.2, 2.0, 0.5).unwrap()),
        ],
    ];
    let origin = [3.0, -4.0];
    let pose = Pose::raised(origin[0], origin[1], 0.7, 30.0).unwrap();
    for model in models.map(|factors| ClutterModel::new(factors).unwrap()) {
        let k = model.metadata_columns();
        for m in [1, 3, 4, 5, 9, 130] {
            let mut positions: Vec<f64> = (0..2 * m)
                .map(|k| ((k as f64) * 0.618_033_988_749_895).sin() * 1500.0)
                .collect();
            // on the band edges exactly, far away, and positions that cannot be used
            positions[0] = origin[0] + 100.0;
            positions[1] = origin[1];
            if m > 4 {
                positions[8] = origin[0] + 1000.0;
                positions[9] = origin[1];
                positions[6] = 1e300;
            }
            if m > 100 {
                positions[2 * 77 + 1] = f64::NAN;
                positions[2 * 90] = f64::NEG_INFINITY;
            }
            let metadata: Vec<f64> = (0..k * m)
                .map(|k| match k % 7 {
                    0 => f64::NAN,
                    1 => 10.0,
                    2 => 0.5,
                    _ => (k % 23) as f64,
                })
                .collect();
            let ranges: Vec<f64> = (0..m).map(|i| if i % 3 == 0 { 1000.0 } else { f64::NAN }).collect();
            // heights around the sensor's (30 m): some on it, some far above, one not finite
            let mut heights: Vec<f64> = (0..m).map(|i| ((i as f64) * 0.37).cos() * 200.0 + 30.0).collect();
            heights[0] = 30.0;
            if m > 100 {
                heights[101] = f64::NAN;
            }
            let height_options: &[Option<&[f64]>] = if model.uses_height() {
                &[Some(&heights)]
            } else {
                &[None, Some(&heights)]
            };
            for (ranges, &heights) in [None, Some(&ranges[..])]
                .into_iter()
                .flat_map(|r| height_options.iter().map(move |h| (r, h)))
            {
                // the rows the kernel reads: (x, y), or (x, y, z) with the heights
                let (rows, ncols): (Vec<f64>, usize) = match heights {
                    None => (positions.clone(), 2),
                    Some(h) => (
                        (0..m)
                            .flat_map(|i| [positions[2 * i], positions[2 * i + 1], h[i]])
                            .collect(),
                        3,
                    ),
                };
                let reference: Vec<u64> = (0..m)
                    .map(|i| {
                        model
                            .at_one(
                                &pose,
                                [positions[2 * i], positions[2 * i + 1]],
                                heights.map(|h| h[i]),
                                &metadata[k * i..k * (i + 1)],
                                ranges.map_or(f64::NAN, |r| r[i]),
                            )
                            .to_bits()
                    })
                    .collect();
                let first_bad = reference.iter().position(|&v| !is_density(f64::from_bits(v)));
                for backend in [Backend::Portable, Backend::Avx2].into_iter().filter(|b| b.available()) {
                    let mut out = vec![0.0; m];
                    let bad = run_on(
                        backend,
                        Densities {
                            model: &model,
                            pose: &pose,
                            positions: &rows,
                            ncols,
                            metadata: &metadata,
                            ranges,
                            first: 0,
                            out: &mut out,
                        },
                    );
                    assert_eq!(
                        out.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                        reference,
                        "{backend:?} m={m} {model:?}"
                    );
                    assert_eq!(bad, first_bad, "{backend:?} m={m} {model:?}");
                }
            }
        }
    }
}

#[test]
fn a_model_reading_heights_needs_them_and_names_a_bad_one() {
    let sector = ElevationSector::new(-0.1, 0.05, 8.0, 1.0).unwrap();
    let model = ClutterModel::new(vec![ClutterFactor::Elevation(sector)]).unwrap();
    assert!(model.uses_height());
    let pose = Pose::raised(0.0, 0.0, 0.0, 20.0).unwrap();
    let mut out = [0.0; 2];
    let positions = [1000.0, 0.0, 1000.0, 0.0];
    let err = model.evaluate(&pose, &positions, &[], &mut out).unwrap_err();
    assert_eq!(err.argument(), "positions");
    // 1 km out: at the sea (elevation −1.1°, inside) and 500 m up (+26°, outside)
    model
        .evaluate_rows(&pose, &[1000.0, 0.0, 0.0, 1000.0, 0.0, 500.0], 3, &[], None, &mut out)
        .unwrap();
    assert_eq!(out, [8.0, 1.0]);
    let err = model
        .evaluate_rows(
            &pose,
            &[1000.0, 0.0, 0.0, 1000.0, 0.0, f64::NAN],
            3,
            &[],
            None,
            &mut out,
        )
        .unwrap_err();
    assert_eq!(err.argument(), "positions");
    assert!(err.to_string().contains("row 1"), "{err}");
    let err = model
        .evaluate_rows(&pose, &[1000.0, 0.0, 0.0, 1000.0, 0.0], 3, &[], None, &mut out)
        .unwrap_err();
    assert_eq!(err.argument(), "positions");
    // slant range bands: 1 km out and 1 km up is 1.41 km away
    let bands = RangeBands::new(vec![1200.0], vec![1.0, 2.0], vec![true]).unwrap();
    let model = ClutterModel::new(vec![ClutterFactor::Range(bands)]).unwrap();
    model
        .evaluate_rows(&pose, &[1000.0, 0.0, 20.0, 1000.0, 0.0, 1020.0], 3, &[], None, &mut out)
        .unwrap();
    assert_eq!(out, [1.0, 2.0]);
}
