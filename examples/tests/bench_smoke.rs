//! Smoke test of the bench (`--quick`): it runs every family on two scenes and writes
//! well-formed outputs. It asserts the outputs' shape, never a timing.

use scatter_conformance::gpu;
use scatter_examples::bench::{BenchConfig, run, write_outputs};

#[test]
fn quick_bench_writes_well_formed_outputs() {
    let Some(ctx) = gpu() else { return };
    let config = BenchConfig::quick();
    let result = run(ctx, &config, false).unwrap_or_else(|e| panic!("bench: {e}"));
    assert_eq!(result.rows.len(), config.cases.len() * config.methods.len());
    for r in &result.rows {
        assert_eq!(r.non_finite, 0, "{} {} {}", r.variant, r.scene, r.pose);
        assert!(r.rel_l1_exact.is_finite() && r.rel_l1_shadow_map.is_finite());
        assert!(!r.passes.is_empty());
    }
    let dir = std::env::temp_dir().join(format!("scatter-bench-smoke-{}", std::process::id()));
    let written = write_outputs(&result, &dir, "bench --quick").unwrap_or_else(|e| panic!("{e}"));
    let csv = std::fs::read_to_string(dir.join("bench.csv")).unwrap_or_else(|e| panic!("{e}"));
    let mut lines = csv.lines();
    let header: Vec<_> = lines.next().unwrap_or_default().split(',').collect();
    assert_eq!(header.len(), 10, "{header:?}");
    let body: Vec<_> = lines.collect();
    assert_eq!(body.len(), result.rows.len());
    for l in &body {
        let cells: Vec<_> = l.split(',').collect();
        assert_eq!(cells.len(), header.len(), "{l}");
        for i in [4, 5, 7] {
            let v: f64 = cells[i].parse().unwrap_or_else(|e| panic!("{l}: {e}"));
            assert!(v.is_finite() && v >= 0.0, "{l}");
        }
    }
    let md = std::fs::read_to_string(dir.join("bench.md")).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        md.contains("## Ratios") && md.contains("| prefiltered |") && md.contains("| raymarch |")
    );
    if written.iter().any(|p| p.ends_with("bench.svg")) {
        let svg = std::fs::read_to_string(dir.join("bench.svg")).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            svg.starts_with("<svg") && svg.contains("Pareto front"),
            "{}",
            &svg[..svg.len().min(200)]
        );
        let png = std::fs::read(dir.join("bench.png")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    } else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI installs fonts-dejavu-core: the chart must be drawn"
        );
        eprintln!("bench smoke: no DejaVu Sans font installed, so no chart (tables checked)");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
