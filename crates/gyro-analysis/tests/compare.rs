//! Comparison of designs: side-by-side table (terminal and Markdown) and the overlay plot.
#![allow(clippy::unwrap_used)]

use crate::common;

use common::{Spec, damped, temp_dir, write_run};
use gyro_analysis::compare;

#[test]
fn compares_designs_side_by_side_with_a_plot() {
    let dir = temp_dir("compare");
    for (name, period, dec) in [("anschutz", 3800.0, 0.3), ("sperry", 5060.0, 0.8)] {
        write_run(
            &dir.join(format!("{name}.mcap")),
            &Spec {
                design: name.into(),
                error: Box::new(damped(0.001, 0.0, 0.05, dec / period, period, 0.0)),
                ..Spec::default()
            },
        );
    }
    let out = dir.join("report");
    let report = compare(&[dir.join("*.mcap")], &out).unwrap();
    let text = report.render_terminal();
    assert!(
        text.contains("anschutz") && text.contains("sperry"),
        "{text}"
    );
    assert!(
        text.contains("period (min)") && text.contains("63.33"),
        "{text}"
    );
    let md = report.render_markdown();
    assert!(md.starts_with("| metric | anschutz | sperry |"), "{md}");
    assert!(md.contains("reading_error.png"));
    let svg = std::fs::read_to_string(report.plot_svg.as_ref().unwrap()).unwrap();
    assert!(svg.starts_with("<svg") && svg.matches("<polyline").count() >= 4);
    let png = std::fs::read(report.plot_png.as_ref().unwrap()).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
}
