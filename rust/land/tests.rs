//! Unit tests of the land mask: validation, and its containment index against the exact count.

use super::*;

fn square(x0: f64, y0: f64, size: f64) -> Vec<Point> {
    vec![[x0, y0], [x0 + size, y0], [x0 + size, y0 + size], [x0, y0 + size]]
}

#[test]
fn square_with_hole() {
    let mask = LandMask::new(vec![Polygon {
        shell: square(0.0, 0.0, 10.0),
        holes: vec![square(4.0, 4.0, 2.0)],
    }])
    .unwrap();
    assert!(mask.contains([1.0, 1.0]));
    assert!(!mask.contains([5.0, 5.0]));
    assert!(!mask.contains([11.0, 5.0]));
    assert!(mask.contains([0.0, 5.0]), "boundary is land");
    assert!(mask.contains([4.0, 5.0]), "hole boundary is land");
    assert!(mask.contains([10.0, 10.0]), "vertex is land");
}

#[test]
fn orientation_and_closing_vertex_do_not_matter() {
    let mut cw = square(0.0, 0.0, 10.0);
    cw.reverse();
    cw.push(cw[0]);
    let mask = LandMask::new(vec![Polygon {
        shell: cw,
        holes: vec![],
    }])
    .unwrap();
    assert!(mask.contains([3.0, 3.0]));
    assert_eq!(mask.polygons()[0].shell.len(), 4);
}

#[test]
fn index_agrees_with_exact_count_on_a_jagged_ring() {
    // A star with many spikes, queried on a dense lattice that hits vertex x's exactly.
    let n = 400;
    let shell: Vec<Point> = (0..n)
        .map(|k| {
            let t = k as f64 / n as f64 * std::f64::consts::TAU;
            let r = if k % 2 == 0 { 100.0 } else { 40.0 + (k % 7) as f64 };
            [r * t.cos(), r * t.sin()]
        })
        .collect();
    let mask = LandMask::new(vec![Polygon { shell, holes: vec![] }]).unwrap();
    let mut land = 0;
    for xi in -110..=110 {
        for yi in -110..=110 {
            let p = [xi as f64 * 1.0 + 0.25, yi as f64 * 1.0];
            let got = mask.contains(p);
            assert_eq!(got, contains_exact(mask.edges(), p), "at {p:?}");
            land += got as usize;
        }
    }
    assert!(land > 1000);
}

/// Integer vertices and integer queries put walks exactly through vertices (the exact
/// row fallback); a dense zigzag makes cells split into sub-cells.
#[test]
fn index_agrees_with_exact_count_on_integer_coastline_with_split_cells() {
    // A comb: 400 teeth 0.25 wide and 40 tall on top of a 60-high block, plus a hole.
    let mut shell = vec![[0.0, 0.0], [100.0, 0.0]];
    for k in (0..400).rev() {
        let x = 0.25 * k as f64;
        shell.push([x + 0.25, 60.0]);
        shell.push([x + 0.125, 100.0]);
    }
    shell.push([0.0, 60.0]);
    let hole = vec![[10.0, 10.0], [30.0, 10.0], [30.0, 30.0], [10.0, 30.0]];
    let mask = LandMask::new(vec![Polygon {
        shell,
        holes: vec![hole],
    }])
    .unwrap();
    assert!(
        mask.grid.split > 0 && !mask.grid.sub_slots.is_empty(),
        "the comb should split cells"
    );
    let mut land = 0;
    for xi in -2..=402 {
        for yi in -2..=410 {
            let p = [xi as f64 * 0.25, yi as f64 * 0.25];
            let got = mask.contains(p);
            assert_eq!(got, contains_exact(mask.edges(), p), "at {p:?}");
            land += got as usize;
        }
    }
    assert!(land > 80_000, "{land}");
    for p in [
        [-1e9, 5.0],
        [5.0, 1e9],
        [1e300, -1e300],
        [f64::INFINITY, 5.0],
        [f64::NAN, 5.0],
        [5.0, f64::NAN],
    ] {
        assert!(!mask.contains(p), "{p:?}");
    }
}

#[test]
fn invalid_polygons_are_rejected() {
    let bowtie = vec![[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 6.0]];
    let err = LandMask::new(vec![Polygon {
        shell: bowtie,
        holes: vec![],
    }])
    .unwrap_err();
    assert_eq!(err.argument(), "polygons");
    assert!(err.to_string().contains("cross"));
    let two = vec![[0.0, 0.0], [1.0, 1.0], [0.0, 0.0]];
    assert!(LandMask::new(vec![Polygon {
        shell: two,
        holes: vec![]
    }])
    .unwrap_err()
    .to_string()
    .contains("3 distinct"));
    let line = vec![[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]];
    assert!(LandMask::new(vec![Polygon {
        shell: line,
        holes: vec![]
    }])
    .unwrap_err()
    .to_string()
    .contains("zero area"));
    let touching_hole = Polygon {
        shell: square(0.0, 0.0, 10.0),
        holes: vec![square(0.0, 4.0, 2.0)],
    };
    assert!(LandMask::new(vec![touching_hole]).is_err());
    let outside_hole = Polygon {
        shell: square(0.0, 0.0, 10.0),
        holes: vec![square(20.0, 4.0, 2.0)],
    };
    assert!(LandMask::new(vec![outside_hole])
        .unwrap_err()
        .to_string()
        .contains("outside its shell"));
    let overlapping = vec![
        Polygon {
            shell: square(0.0, 0.0, 10.0),
            holes: vec![],
        },
        Polygon {
            shell: square(2.0, 2.0, 2.0),
            holes: vec![],
        },
    ];
    assert!(LandMask::new(overlapping)
        .unwrap_err()
        .to_string()
        .contains("lies on the land"));
    let nan = vec![[0.0, 0.0], [f64::NAN, 1.0], [2.0, 0.0]];
    assert!(LandMask::new(vec![Polygon {
        shell: nan,
        holes: vec![]
    }])
    .unwrap_err()
    .to_string()
    .contains("not finite"));
}

#[test]
fn tiny_rings_are_valid_land() {
    for size in [1e-200, 1e-300, 5e-320, 2.0 * TINY] {
        let mask = LandMask::new(vec![Polygon {
            shell: vec![[0.0, 0.0], [size, 0.0], [0.0, size]],
            holes: vec![],
        }])
        .unwrap();
        assert_eq!(
            mask.polygons()[0].shell,
            vec![[0.0, 0.0], [size, 0.0], [0.0, size]],
            "world coordinates kept"
        );
        assert!(mask.contains([size / 4.0, size / 4.0]));
        assert!(mask.contains([size, 0.0]), "vertex is land");
        assert!(!mask.contains([0.75 * size, 0.75 * size]));
        assert!(!mask.contains([-size, 0.0]));
        assert!(!mask.contains([1.0, 1.0]) && !mask.contains([1e300, 0.0]));
    }
    let line = vec![[0.0, 0.0], [1e-200, 1e-200], [2e-200, 2e-200]];
    assert!(LandMask::new(vec![Polygon {
        shell: line,
        holes: vec![]
    }])
    .unwrap_err()
    .to_string()
    .contains("zero area"));
    // Next to a 1 km island a 1e-200 m rock cannot be represented: said so, not "zero area".
    let rock = Polygon {
        shell: vec![[0.0, 0.0], [1e-200, 0.0], [0.0, 1e-200]],
        holes: vec![],
    };
    let err = LandMask::new(vec![
        Polygon {
            shell: square(500.0, 500.0, 1000.0),
            holes: vec![],
        },
        rock,
    ])
    .unwrap_err();
    assert!(err.to_string().contains("too small"), "{err}");
}

#[test]
fn huge_rings_are_valid_land() {
    for size in [1e160, 1e300, f64::MAX / 2.0, 2.0 * HUGE] {
        let mask = LandMask::new(vec![Polygon {
            shell: vec![[0.0, 0.0], [size, 0.0], [0.0, size]],
            holes: vec![],
        }])
        .unwrap();
        assert_eq!(
            mask.polygons()[0].shell,
            vec![[0.0, 0.0], [size, 0.0], [0.0, size]],
            "world coordinates kept"
        );
        assert!(mask.contains([size / 4.0, size / 4.0]));
        assert!(mask.contains([size, 0.0]), "vertex is land");
        assert!(!mask.contains([0.75 * size, 0.75 * size]));
        assert!(!mask.contains([-size, 0.0]) && !mask.contains([1.0, -1.0]));
    }
    let bowtie = vec![[0.0, 0.0], [1e300, 1e300], [1e300, 0.0], [0.0, 1e300]];
    assert!(LandMask::new(vec![Polygon {
        shell: bowtie,
        holes: vec![]
    }])
    .is_err());
}

#[test]
fn island_in_a_lake_is_land() {
    let polygons = vec![
        Polygon {
            shell: square(0.0, 0.0, 10.0),
            holes: vec![square(2.0, 2.0, 6.0)],
        },
        Polygon {
            shell: square(4.0, 4.0, 2.0),
            holes: vec![],
        },
    ];
    let mask = LandMask::new(polygons).unwrap();
    assert!(mask.contains([5.0, 5.0]));
    assert!(!mask.contains([3.0, 3.0]));
    assert!(mask.contains([1.0, 1.0]));
}
