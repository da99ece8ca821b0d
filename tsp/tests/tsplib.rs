//! TSPLIB reader: formats, distance functions, errors, shared instances.
mod common;

use common::read_best;
use sornav_tsp::tsplib::{self, ProblemKind, TsplibError};

fn explicit(kind: &str, format: &str, body: &str, n: usize) -> String {
    format!(
        "NAME : t\nTYPE : {kind}\nDIMENSION : {n}\nEDGE_WEIGHT_TYPE : EXPLICIT\nEDGE_WEIGHT_FORMAT : {format}\nEDGE_WEIGHT_SECTION\n{body}\nEOF\n"
    )
}

/// The symmetric 4x4 matrix with d(i, j) = 10 * (min + 1) + (max + 1) for
/// i != j, written in every triangular format.
#[test]
fn every_explicit_format_gives_the_same_matrix() {
    let d = |i: usize, j: usize| {
        if i == j {
            0.0
        } else {
            (10 * (i.min(j) + 1) + i.max(j) + 1) as f64
        }
    };
    let n = 4;
    let mut cases = Vec::new();
    let collect = |pairs: &mut dyn Iterator<Item = (usize, usize)>| {
        pairs
            .map(|(i, j)| format!("{}", d(i, j)))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let upper_row = collect(&mut (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))));
    let lower_row = collect(&mut (0..n).flat_map(|i| (0..i).map(move |j| (i, j))));
    let upper_diag_row = collect(&mut (0..n).flat_map(|i| (i..n).map(move |j| (i, j))));
    let lower_diag_row = collect(&mut (0..n).flat_map(|i| (0..=i).map(move |j| (i, j))));
    // Column-wise: column j lists rows i of the triangle.
    let upper_col = collect(&mut (0..n).flat_map(|j| (0..j).map(move |i| (i, j))));
    let lower_col = collect(&mut (0..n).flat_map(|j| (j + 1..n).map(move |i| (i, j))));
    let upper_diag_col = collect(&mut (0..n).flat_map(|j| (0..=j).map(move |i| (i, j))));
    let lower_diag_col = collect(&mut (0..n).flat_map(|j| (j..n).map(move |i| (i, j))));
    let full = collect(&mut (0..n).flat_map(|i| (0..n).map(move |j| (i, j))));
    cases.push(("FULL_MATRIX", full));
    cases.push(("UPPER_ROW", upper_row));
    cases.push(("LOWER_ROW", lower_row));
    cases.push(("UPPER_DIAG_ROW", upper_diag_row));
    cases.push(("LOWER_DIAG_ROW", lower_diag_row));
    cases.push(("UPPER_COL", upper_col));
    cases.push(("LOWER_COL", lower_col));
    cases.push(("UPPER_DIAG_COL", upper_diag_col));
    cases.push(("LOWER_DIAG_COL", lower_diag_col));
    for (format, body) in cases {
        // Spread numbers over irregular lines, as real files do.
        let body = body.replacen(' ', "\n", 2);
        let inst = tsplib::parse(&explicit("TSP", format, &body, n)).unwrap();
        assert_eq!(inst.kind, ProblemKind::Symmetric);
        for i in 0..n {
            for j in 0..n {
                assert_eq!(inst.matrix.cost(i, j), d(i, j), "{format} ({i},{j})");
            }
        }
    }
}

#[test]
fn atsp_full_matrix_keeps_asymmetry_and_other_formats_are_rejected() {
    let inst = tsplib::parse(&explicit(
        "ATSP",
        "FULL_MATRIX",
        "9999 1 2\n3 9999 4\n5 6 9999",
        3,
    ))
    .unwrap();
    assert_eq!(inst.kind, ProblemKind::Asymmetric);
    assert_eq!((inst.matrix.cost(0, 1), inst.matrix.cost(1, 0)), (1.0, 3.0));
    assert!(matches!(
        tsplib::parse(&explicit("ATSP", "UPPER_ROW", "1 2 3", 3)),
        Err(TsplibError::UnsupportedFormat { .. })
    ));
}

/// TSPLIB95's truncated pi used by `GEO`.
#[allow(clippy::approx_constant)]
const TSPLIB_PI: f64 = 3.141592;

/// Expected error shape.
type Check = fn(&TsplibError) -> bool;

fn coords(kind: &str, pts: &[(f64, f64)]) -> String {
    let mut s = format!(
        "NAME: c\nTYPE: TSP\nDIMENSION: {}\nEDGE_WEIGHT_TYPE: {kind}\nNODE_COORD_SECTION\n",
        pts.len()
    );
    for (i, (x, y)) in pts.iter().enumerate() {
        s += &format!("{} {x} {y}\n", i + 1);
    }
    s + "EOF\n"
}

#[test]
fn distance_functions_follow_tsplib95() {
    // EUC_2D rounds to nearest: sqrt(2) * 1.5 = 2.12 -> 2, 2.5 -> 3.
    let m = tsplib::parse(&coords("EUC_2D", &[(0.0, 0.0), (1.5, 1.5), (2.5, 0.0)]))
        .unwrap()
        .matrix;
    assert_eq!((m.cost(0, 1), m.cost(0, 2)), (2.0, 3.0));
    // CEIL_2D rounds up.
    let m = tsplib::parse(&coords("CEIL_2D", &[(0.0, 0.0), (1.5, 1.5), (2.0, 0.0)]))
        .unwrap()
        .matrix;
    assert_eq!((m.cost(0, 1), m.cost(0, 2)), (3.0, 2.0));
    // ATT: r = sqrt(d^2 / 10); 100 -> 31.62 -> 32; sqrt(90^2/10) = 28.46 -> 29 (t < r bumps up).
    let m = tsplib::parse(&coords(
        "ATT",
        &[(0.0, 0.0), (100.0, 0.0), (0.0, 90.0), (0.0, 10.0)],
    ))
    .unwrap()
    .matrix;
    assert_eq!((m.cost(0, 1), m.cost(0, 2)), (32.0, 29.0));
    // sqrt(100 / 10) = 3.162 -> nint 3 < r -> 4.
    assert_eq!(m.cost(0, 3), 4.0);
    // GEO: one degree of longitude on the equator = 6378.388 * 3.141592 / 180
    // = 111.32 -> +1 -> 112 (truncated); "1.30" means 1 deg 30 min = 1.5 deg.
    let m = tsplib::parse(&coords("GEO", &[(0.0, 0.0), (0.0, 1.0), (0.0, 1.30)]))
        .unwrap()
        .matrix;
    assert_eq!(m.cost(0, 1), 112.0);
    assert_eq!(
        m.cost(0, 2),
        (6378.388 * TSPLIB_PI * 1.5 / 180.0 + 1.0_f64).trunc()
    );
}

#[test]
fn malformed_files_are_typed_errors() {
    let ok = coords("EUC_2D", &[(0.0, 0.0), (1.0, 0.0)]);
    assert!(tsplib::parse(&ok).is_ok());
    let cases: Vec<(String, Check)> = vec![
        (ok.replace("TYPE: TSP", "TYPE: CVRP"), |e| {
            matches!(e, TsplibError::UnsupportedType(_))
        }),
        (ok.replace("EUC_2D", "EUC_3D"), |e| {
            matches!(e, TsplibError::UnsupportedWeightType(_))
        }),
        (ok.replace("DIMENSION: 2", "DIMENSION: 0"), |e| {
            matches!(e, TsplibError::BadDimension(_))
        }),
        (ok.replace("DIMENSION: 2", "DIMENSION: x"), |e| {
            matches!(e, TsplibError::BadDimension(_))
        }),
        (ok.replace("DIMENSION: 2\n", ""), |e| {
            matches!(e, TsplibError::Missing(_))
        }),
        (ok.replace("TYPE: TSP\n", ""), |e| {
            matches!(e, TsplibError::Missing("TYPE"))
        }),
        (ok.replace("2 1 0", "2 1 zz"), |e| {
            matches!(e, TsplibError::BadNumber { line: 7, .. })
        }),
        (ok.replace("2 1 0", "2 1 NaN"), |e| {
            matches!(e, TsplibError::BadNumber { .. })
        }),
        (ok.replace("2 1 0", "1 1 0"), |e| {
            matches!(e, TsplibError::BadNode { id: 1, .. })
        }),
        (ok.replace("2 1 0", "3 1 0"), |e| {
            matches!(e, TsplibError::BadNode { id: 3, .. })
        }),
        (ok.replace("2 1 0\n", ""), |e| {
            matches!(e, TsplibError::WrongCount { .. })
        }),
        (
            ok.replace("NODE_COORD_SECTION", "FIXED_EDGES_SECTION"),
            |e| matches!(e, TsplibError::UnsupportedSection { .. }),
        ),
        (ok.replace("NODE_COORD_SECTION\n1 0 0\n2 1 0\n", ""), |e| {
            matches!(e, TsplibError::MissingSection(_))
        }),
        (ok.replace("NAME: c", "what is this"), |e| {
            matches!(e, TsplibError::Syntax { line: 1, .. })
        }),
        (explicit("TSP", "UPPER_ROW", "1 2", 3), |e| {
            matches!(e, TsplibError::WrongCount { .. })
        }),
        (explicit("TSP", "WEIRD", "1 2 3", 3), |e| {
            matches!(e, TsplibError::UnsupportedFormat { .. })
        }),
        (
            explicit("TSP", "UPPER_ROW", "1 2 3", 3)
                .replace("EDGE_WEIGHT_FORMAT : UPPER_ROW\n", ""),
            |e| matches!(e, TsplibError::Missing(_)),
        ),
        (explicit("TSP", "UPPER_ROW", "1 2 1e400", 3), |e| {
            matches!(e, TsplibError::BadNumber { .. })
        }),
    ];
    for (text, check) in cases {
        let err = tsplib::parse(&text).expect_err(&text);
        assert!(check(&err), "{text}\n=> {err:?}");
    }
    assert!(matches!(
        tsplib::read("/definitely/not/here.tsp"),
        Err(TsplibError::Io { .. })
    ));
    assert!(matches!(
        tsplib::parse_tour("TYPE: TOUR\nEOF\n"),
        Err(TsplibError::MissingSection(_))
    ));
    assert!(matches!(
        tsplib::parse_tour("DIMENSION: 3\nTOUR_SECTION\n1 2 4 -1\n"),
        Err(TsplibError::BadNode { id: 4, .. })
    ));
    assert!(matches!(
        tsplib::parse_tour("DIMENSION: 3\nTOUR_SECTION\n1 2 -1\n"),
        Err(TsplibError::WrongCount { .. })
    ));
    assert_eq!(
        tsplib::parse_tour("TOUR_SECTION\n3 1 2\n-1\nEOF\n").unwrap(),
        vec![2, 0, 1]
    );
}

/// Every shared TSPLIB instance parses, and each published optimal tour
/// prices exactly at the proven optimum (checks the distance functions on
/// real data).
#[test]
fn shared_instances_parse_and_optimal_tours_match_best_solutions() {
    let Some(dir) = sornav_test_support::shared_data("tsplib") else {
        return;
    };
    let best = read_best(&dir.join("tsp/bestSolutions.txt"));
    let mut tours = 0;
    for sub in ["tsp", "atsp"] {
        for entry in std::fs::read_dir(dir.join(sub)).unwrap() {
            let path = entry.unwrap().path();
            let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
            if ext != "tsp" && ext != "atsp" {
                continue;
            }
            let inst = tsplib::read(&path).unwrap();
            let tour_path = path.with_extension("opt.tour");
            if tour_path.is_file() {
                let tour = tsplib::read_tour(&tour_path).unwrap();
                let opt = best[&inst.name];
                assert_eq!(inst.matrix.tour_cost(&tour).unwrap(), opt, "{}", inst.name);
                tours += 1;
            }
        }
    }
    assert!(tours >= 10, "only {tours} optimal tours checked");
}
