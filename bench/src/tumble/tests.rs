//! B1 on small meshes: every algorithm agrees, the figure sweep runs.

use super::*;
use crate::baselines::ObbTree;
use vas_server::collision::{MeshCollider, QueryStats};
use vas_server::geometry::shapes;

#[test]
fn tumble_runs_every_algorithm_without_mismatch() {
    let mesh = shapes::torus(1.0, 0.35, 20, 10);
    let config = TumbleConfig {
        steps: 40,
        distances: vec![2.5, 1.0],
        algos: vec![
            Algo::Doptree,
            Algo::DoptreePar,
            Algo::KdopBruteforce,
            Algo::Obbtree,
            Algo::Parry,
        ],
        orientations: OrientationSet::default(),
        rounds: 2,
    };
    let report = run_tumble(&mesh, &mesh, &config).unwrap();
    assert_eq!(report.mismatches, 0);
    assert_eq!(report.results.len(), 10);
    let far = &report.results[0];
    let near = report
        .results
        .iter()
        .find(|r| r.distance == Some(1.0))
        .unwrap();
    assert!(far.hit_fraction < near.hit_fraction);
    assert!(near.hit_fraction > 0.9, "a torus through a torus at d = 1");
    let json = serde_json::to_value(&report).unwrap();
    for key in [
        "algo",
        "distance",
        "mean_us",
        "max_us",
        "hit_fraction",
        "bv_tests",
        "realignments",
        "tri_tests",
    ] {
        assert!(json["results"][0].get(key).is_some(), "{key}");
    }
    assert!(
        results_table(&report.results)
            .render()
            .contains("kdop-bruteforce")
    );
    for reference in ["empty_query", "sphere_test"] {
        for key in ["mean_us", "pass_mean_us"] {
            let value = json["floor"][reference][key].as_f64().unwrap();
            assert!(
                value.is_finite() && value >= 0.0,
                "{reference}.{key}: {value}"
            );
        }
    }
}

#[test]
fn a_turns_untimed_first_query_is_not_counted() {
    let mesh = shapes::torus(1.0, 0.35, 20, 10).normalized_to_unit_box();
    let set = OrientationSet::default();
    let poses: Vec<_> = (0..30).map(|s| tumble_pose(1.0, s, 30)).collect();
    let collider = BuiltCollider::new(Algo::Obbtree, &mesh, &mesh, &set);
    let (results, _) = run_poses(std::slice::from_ref(&collider), &poses, Some(1.0), 2);
    // The OBB-tree keeps no memory between queries, so each pose's counters are its own.
    let tree = ObbTree::build(&mesh);
    let mut expected = QueryStats::default();
    let hits = poses
        .iter()
        .filter(|pose| tree.intersects(&tree, pose, &mut expected))
        .count();
    let n = poses.len() as f64;
    assert_eq!(results[0].bv_tests, expected.bv_tests as f64 / n);
    assert_eq!(results[0].tri_tests, expected.tri_tests as f64 / n);
    assert_eq!(results[0].hit_fraction, hits as f64 / n);
}

#[test]
fn non_finite_distances_are_refused() {
    let mesh = shapes::torus(1.0, 0.35, 8, 4);
    for d in [f64::NAN, f64::INFINITY] {
        let config = TumbleConfig {
            steps: 4,
            distances: vec![2.0, d],
            algos: vec![Algo::Obbtree],
            orientations: OrientationSet::default(),
            rounds: 1,
        };
        let error = run_tumble(&mesh, &mesh, &config).unwrap_err();
        assert!(error.to_string().contains("finite"), "{error}");
    }
}

#[test]
fn algorithm_names_round_trip() {
    use clap::ValueEnum;
    for algo in Algo::value_variants() {
        assert_eq!(Algo::from_str(algo.name(), false).unwrap(), *algo);
    }
    assert!(Algo::from_str("rapid", false).is_err());
}
