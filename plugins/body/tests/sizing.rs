//! Size charts (seed 002 Tables 4.2 and 4.3, EN 13402) and size recommendation: the chart files
//! in `assets/sizecharts` load and reproduce the seed tables, recommendations at nominal
//! values, boundaries, gaps and beyond the chart, and clear errors for malformed files.

use std::path::{Path, PathBuf};

use fitroom_body::sizing::recommend_with;
use fitroom_body::{
    ChartProblem, FitAtSize, Gender, Landmarks, Measure, Measurements, Placement, Recommendation,
    SizeChart, SizeChartError, recommend,
};

fn chart_path(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/sizecharts")
        .join(file)
}

fn load(file: &str) -> SizeChart {
    let path = chart_path(file);
    SizeChart::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn male() -> SizeChart {
    load("en13402-male-seed002.ron")
}

fn female() -> SizeChart {
    load("en13402-female-seed002.ron")
}

fn retailer() -> SizeChart {
    load("example-retailer-tops.ron")
}

/// Measurements with the given values, NaN (unknown) elsewhere.
fn values(given: &[(Measure, f32)]) -> impl Fn(Measure) -> f32 + '_ {
    move |m| {
        given
            .iter()
            .find(|(g, _)| *g == m)
            .map_or(f32::NAN, |&(_, v)| v)
    }
}

fn advice(r: &Recommendation, m: Measure) -> &fitroom_body::MeasureAdvice {
    r.measures
        .iter()
        .find(|a| a.measure == m)
        .unwrap_or_else(|| panic!("no advice for {m} in {r:#?}"))
}

/// Checks that `chart` has the sizes `labels` and, for each measure row of a seed table, the
/// nominal value and the centre of the derived range of every size.
fn assert_table(chart: &SizeChart, labels: &[&str], rows: &[(Measure, &[f32])]) {
    let got: Vec<&str> = chart.sizes.iter().map(|s| s.label.as_str()).collect();
    assert_eq!(got, labels);
    for &(measure, row) in rows {
        assert_eq!(row.len(), labels.len(), "{measure}: test table row length");
        for (size, &value) in chart.sizes.iter().zip(row) {
            let nominal = size.nominal_cm.get(&measure).copied();
            assert_eq!(
                nominal,
                Some(value),
                "size {}, {measure} nominal",
                size.label
            );
            let range = size.ranges_cm[&measure];
            assert_eq!(
                range.centre_cm(),
                value,
                "size {}, {measure}: range {range} not centred on the table value",
                size.label
            );
            assert!(range.min_cm < range.max_cm);
        }
    }
}

#[test]
fn male_chart_reproduces_seed_table_4_2() {
    let chart = male();
    assert_eq!(chart.gender, Gender::Male);
    assert_eq!(chart.primary, vec![Measure::Bust]);
    // Seed 002 Table 4.2, typed from the thesis.
    assert_table(
        &chart,
        &["44", "46", "48", "50", "52", "54", "56"],
        &[
            (
                Measure::ArmLength,
                &[63.0, 63.0, 64.0, 64.0, 64.0, 64.0, 65.0],
            ),
            (Measure::Neck, &[37.0, 38.0, 39.0, 40.0, 41.0, 42.0, 43.0]),
            (
                Measure::Bust,
                &[88.0, 92.0, 96.0, 100.0, 104.0, 108.0, 112.0],
            ),
            (Measure::Waist, &[78.0, 82.0, 86.0, 90.0, 94.0, 98.0, 104.0]),
        ],
    );
    assert_eq!(chart.measures().len(), 4);
}

#[test]
fn female_chart_reproduces_seed_table_4_3() {
    let chart = female();
    assert_eq!(chart.gender, Gender::Female);
    assert_eq!(chart.primary, vec![Measure::Bust]);
    // Seed 002 Table 4.3, typed from the thesis.
    assert_table(
        &chart,
        &["34", "36", "38", "40", "42", "44", "46", "48", "50", "52"],
        &[
            (
                Measure::ArmLength,
                &[59.0, 59.0, 60.0, 60.0, 61.0, 61.0, 61.0, 61.0, 62.0, 62.0],
            ),
            (
                Measure::Neck,
                &[34.0, 35.0, 36.0, 37.0, 38.0, 39.0, 40.0, 41.0, 42.0, 43.0],
            ),
            (
                Measure::Bust,
                &[
                    80.0, 84.0, 88.0, 92.0, 96.0, 100.0, 104.0, 110.0, 116.0, 122.0,
                ],
            ),
            (
                Measure::Underbust,
                &[
                    65.0, 70.0, 75.0, 80.0, 85.0, 90.0, 95.0, 100.0, 105.0, 110.0,
                ],
            ),
            (
                Measure::Waist,
                &[62.0, 66.0, 70.0, 74.0, 78.0, 82.0, 86.0, 92.0, 98.0, 104.0],
            ),
            (
                Measure::Hip,
                &[
                    86.0, 90.0, 94.0, 98.0, 102.0, 106.0, 110.0, 116.0, 122.0, 128.0,
                ],
            ),
        ],
    );
}

#[test]
fn nominal_values_become_centred_ranges() {
    let chart = male();
    let range = |label: &str, m: Measure| chart.size(label).unwrap().ranges_cm[&m].to_string();
    // Regular 4 cm steps: ranges touch halfway.
    assert_eq!(range("44", Measure::Bust), "86-90");
    assert_eq!(range("48", Measure::Bust), "94-98");
    assert_eq!(range("56", Measure::Bust), "110-114");
    // The step grows from 4 to 6 cm: centred ranges with a gap between them.
    assert_eq!(range("54", Measure::Waist), "96-100");
    assert_eq!(range("56", Measure::Waist), "101-107");
    // Sizes sharing a nominal value share its range.
    assert_eq!(range("44", Measure::ArmLength), "62.5-63.5");
    assert_eq!(range("46", Measure::ArmLength), "62.5-63.5");
    assert_eq!(range("48", Measure::ArmLength), "63.5-64.5");
}

#[test]
fn retailer_chart_has_letter_sizes_with_ranges() {
    let chart = retailer();
    let labels: Vec<&str> = chart.sizes.iter().map(|s| s.label.as_str()).collect();
    assert_eq!(labels, ["XS", "S", "M", "L", "XL"]);
    assert_eq!(chart.primary, vec![Measure::Bust]);
    assert_eq!(
        chart.measures(),
        vec![Measure::Bust, Measure::Waist, Measure::Hip]
    );
    let m = chart.size("M").unwrap();
    assert_eq!(m.ranges_cm[&Measure::Bust].to_string(), "87-93");
    assert!(m.nominal_cm.is_empty());
}

#[test]
fn recommends_the_size_of_a_body_at_nominal_values() {
    let chart = male();
    // Every measure at size 48's nominal value.
    let r = recommend_with(
        &chart,
        values(&[
            (Measure::ArmLength, 64.0),
            (Measure::Neck, 39.0),
            (Measure::Bust, 96.0),
            (Measure::Waist, 86.0),
        ]),
    );
    assert_eq!(r.size.as_deref(), Some("48"));
    assert_eq!(r.decided_by, vec![Measure::Bust]);
    assert!(r.also_fits.is_empty());
    assert!(r.too_small_for.is_empty());
    assert_eq!(advice(&r, Measure::Bust).reason, "bust 96.0 cm: 48 (94-98)");
    assert_eq!(
        advice(&r, Measure::Neck).reason,
        "neck 39.0 cm: 48 (38.5-39.5)"
    );
    assert_eq!(
        advice(&r, Measure::Waist).reason,
        "waist 86.0 cm: 48 (84-88)"
    );
    // Arm length 64 is size 48 to 54's nominal value.
    assert_eq!(
        advice(&r, Measure::ArmLength).reason,
        "arm-length 64.0 cm: 48 (63.5-64.5) or 50 (63.5-64.5) or 52 (63.5-64.5) or 54 (63.5-64.5)"
    );
    for a in &r.measures {
        assert_eq!(a.at_recommended, FitAtSize::Fits, "{}", a.reason);
    }
    let text = r.to_string();
    assert!(text.starts_with("Recommended size: 48"), "{text}");
    assert!(
        text.contains("  bust 96.0 cm: 48 (94-98) [decides]\n"),
        "{text}"
    );
}

#[test]
fn recommend_takes_a_measurements_value() {
    // Size 40 of seed Table 4.3.
    let m = Measurements {
        stature_cm: 168.0,
        crotch_height_cm: 78.0,
        arm_length_cm: 60.0,
        shoulder_width_cm: 37.0,
        neck_cm: 37.0,
        bust_cm: 92.0,
        underbust_cm: 80.0,
        waist_cm: 74.0,
        navel_waist_cm: 78.0,
        hip_cm: 98.0,
        thigh_cm: 56.0,
        calf_cm: 36.0,
        landmarks: Landmarks::default(),
    };
    let chart = female();
    let r = recommend(&chart, &m);
    assert_eq!(r.size.as_deref(), Some("40"));
    assert_eq!(advice(&r, Measure::Bust).reason, "bust 92.0 cm: 40 (90-94)");
    assert_eq!(
        advice(&r, Measure::Underbust).reason,
        "underbust 80.0 cm: 40 (77.5-82.5)"
    );
    assert_eq!(r, chart.recommend(&m));
}

#[test]
fn a_value_on_a_boundary_fits_both_sizes_and_the_smaller_is_recommended() {
    let chart = male();
    let r = recommend_with(&chart, values(&[(Measure::Bust, 94.0)]));
    assert_eq!(
        advice(&r, Measure::Bust).reason,
        "bust 94.0 cm: 46 (90-94) or 48 (94-98)"
    );
    assert_eq!(r.size.as_deref(), Some("46"));
    assert_eq!(r.also_fits, vec!["48".to_owned()]);
    assert!(r.to_string().contains("Also fits: 48"));
}

#[test]
fn a_value_in_a_gap_gets_the_larger_size() {
    let chart = female();
    let r = recommend_with(&chart, values(&[(Measure::Bust, 106.5)]));
    let bust = advice(&r, Measure::Bust);
    assert_eq!(
        bust.reason,
        "bust 106.5 cm: between 46 (102-106) and 48 (107-113)"
    );
    assert!(matches!(bust.placement, Placement::Between { .. }));
    assert_eq!(r.size.as_deref(), Some("48"));
    assert_eq!(bust.at_recommended, FitAtSize::Loose { by_cm: 0.5 });
}

#[test]
fn below_the_smallest_size() {
    let chart = male();
    let r = recommend_with(
        &chart,
        values(&[(Measure::Bust, 80.0), (Measure::Neck, 37.0)]),
    );
    assert_eq!(r.size.as_deref(), Some("44"));
    let bust = advice(&r, Measure::Bust);
    assert_eq!(
        bust.reason,
        "bust 80.0 cm: below the smallest size 44 (86-90) by 6.0 cm"
    );
    match &bust.placement {
        Placement::BelowSmallest { size, by_cm } => {
            assert_eq!(size.label, "44");
            assert_eq!(*by_cm, 6.0);
        }
        other => panic!("expected below smallest, got {other:?}"),
    }
    assert_eq!(bust.at_recommended, FitAtSize::Loose { by_cm: 6.0 });
    assert!(r.too_small_for.is_empty());
    assert!(r.to_string().contains("44 is loose by 6.0 cm"));
}

#[test]
fn above_the_largest_size() {
    let chart = male();
    let r = recommend_with(&chart, values(&[(Measure::Bust, 120.0)]));
    assert_eq!(r.size.as_deref(), Some("56"));
    let bust = advice(&r, Measure::Bust);
    assert_eq!(
        bust.reason,
        "bust 120.0 cm: above the largest size 56 (110-114) by 6.0 cm"
    );
    assert!(matches!(
        bust.placement,
        Placement::AboveLargest { by_cm, .. } if by_cm == 6.0
    ));
    assert_eq!(bust.at_recommended, FitAtSize::Tight { by_cm: 6.0 });
    assert_eq!(r.too_small_for, vec![Measure::Bust]);
    let text = r.to_string();
    assert!(
        text.contains("Warning: even the largest size is too small for: bust"),
        "{text}"
    );
}

#[test]
fn conflicting_primary_measures_take_the_largest_size() {
    // Table 4.3 as a skirt chart: waist and hip decide.
    let text = std::fs::read_to_string(chart_path("en13402-female-seed002.ron")).unwrap();
    let text = text.replace(r#"primary: ["bust"]"#, r#"primary: ["waist", "hip"]"#);
    let chart = SizeChart::from_ron_str(&text, "skirts.ron").unwrap_or_else(|e| panic!("{e}"));
    let r = recommend_with(
        &chart,
        values(&[
            (Measure::Bust, 92.0),
            (Measure::Waist, 74.0),
            (Measure::Hip, 106.0),
        ]),
    );
    assert_eq!(r.size.as_deref(), Some("44"));
    assert_eq!(r.decided_by, vec![Measure::Hip]);
    assert_eq!(advice(&r, Measure::Waist).needs.as_deref(), Some("40"));
    assert_eq!(
        advice(&r, Measure::Waist).at_recommended,
        FitAtSize::Loose { by_cm: 6.0 }
    );
    assert_eq!(
        advice(&r, Measure::Bust).at_recommended,
        FitAtSize::Loose { by_cm: 6.0 }
    );
    let shown = r.to_string();
    assert!(shown.contains("Decided by hip"), "{shown}");
    assert!(
        shown.contains("  waist 74.0 cm: 40 (72-76); 44 is loose by 6.0 cm [decides]\n"),
        "{shown}"
    );
}

#[test]
fn retailer_chart_reports_tight_and_loose_measures() {
    let chart = retailer();
    let r = recommend_with(
        &chart,
        values(&[
            (Measure::Bust, 90.0),
            (Measure::Waist, 78.0),
            (Measure::Hip, 92.0),
        ]),
    );
    assert_eq!(r.size.as_deref(), Some("M"));
    assert_eq!(advice(&r, Measure::Bust).reason, "bust 90.0 cm: M (87-93)");
    assert_eq!(
        advice(&r, Measure::Waist).reason,
        "waist 78.0 cm: L (75-81)"
    );
    assert_eq!(
        advice(&r, Measure::Waist).at_recommended,
        FitAtSize::Tight { by_cm: 3.0 }
    );
    assert_eq!(
        advice(&r, Measure::Hip).at_recommended,
        FitAtSize::Loose { by_cm: 1.0 }
    );
    let text = r.to_string();
    assert!(
        text.contains("waist 78.0 cm: L (75-81); M is tight by 3.0 cm"),
        "{text}"
    );
    assert!(
        text.contains("hip 92.0 cm: S (88-93); M is loose by 1.0 cm"),
        "{text}"
    );
}

#[test]
fn recommendation_serializes_to_json() {
    let chart = male();
    let r = recommend_with(
        &chart,
        values(&[(Measure::Bust, 96.0), (Measure::Waist, 90.0)]),
    );
    let json = serde_json::to_value(&r).unwrap();
    assert_eq!(json["size"], "48");
    assert_eq!(json["decided_by"][0], "bust");
    let bust = &json["measures"][0];
    assert_eq!(bust["measure"], "bust");
    assert_eq!(bust["placement"]["kind"], "within");
    assert_eq!(bust["placement"]["sizes"][0]["label"], "48");
    assert_eq!(bust["reason"], "bust 96.0 cm: 48 (94-98)");
    let waist = json["measures"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["measure"] == "waist")
        .unwrap();
    assert_eq!(waist["at_recommended"]["kind"], "tight");
    assert_eq!(waist["at_recommended"]["by_cm"], 2.0);
}

#[test]
fn unusable_measurements_do_not_decide() {
    let chart = male();
    // A 3 m waist (a typing error) is reported, not used.
    let r = recommend_with(
        &chart,
        values(&[(Measure::Bust, 96.0), (Measure::Waist, 300.0)]),
    );
    assert_eq!(r.size.as_deref(), Some("48"));
    assert_eq!(
        advice(&r, Measure::Waist).reason,
        "waist 300.0 cm: not used, outside the plausible 45-170 cm"
    );
    // No usable deciding measure: no size.
    let r = recommend_with(&chart, values(&[(Measure::Waist, 86.0)]));
    assert_eq!(r.size, None);
    assert!(r.to_string().starts_with("No size recommended"), "{r}");
}

// ---------------------------------------------------------------------------------------------
// Malformed charts.

const GOOD: &str = r#"(
    name: "test",
    gender: unisex,
    primary: ["bust"],
    sizes: [
        (label: "S", ranges_cm: {"bust": (82, 88), "waist": (64, 70)}),
        (label: "M", ranges_cm: {"bust": (88, 94), "waist": (70, 76)}),
    ],
)"#;

fn load_str(text: &str) -> SizeChartError {
    match SizeChart::from_ron_str(text, "bad.ron") {
        Ok(chart) => panic!("expected an error, loaded {chart:#?}"),
        Err(e) => e,
    }
}

fn problem(text: &str) -> (ChartProblem, String) {
    let e = load_str(text);
    let message = e.to_string();
    assert!(message.starts_with("bad.ron: "), "{message}");
    match e {
        SizeChartError::Invalid { problem, .. } => (*problem, message),
        other => panic!("expected a validation error, got {other}"),
    }
}

#[test]
fn the_test_chart_is_valid() {
    let chart = SizeChart::from_ron_str(GOOD, "good.ron").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(chart.sizes.len(), 2);
}

#[test]
fn syntax_error_names_file_line_and_column() {
    // A missing comma after the name, on line 2.
    let text = GOOD.replace(r#""test","#, r#""test""#);
    let e = load_str(&text);
    let message = e.to_string();
    match e {
        SizeChartError::Syntax { file, line, .. } => {
            assert_eq!(file, "bad.ron");
            assert_eq!(line, 3, "{message}");
        }
        other => panic!("expected a syntax error, got {other}"),
    }
    assert!(message.starts_with("bad.ron:3:"), "{message}");
    assert!(
        message.contains("a size chart is a RON struct"),
        "{message}"
    );
}

#[test]
fn unknown_field_lists_the_known_fields() {
    let text = GOOD.replace(r#"(label: "M", ranges_cm"#, r#"(label: "M", range_cm"#);
    let message = load_str(&text).to_string();
    assert!(message.starts_with("bad.ron:7:"), "{message}");
    for word in ["range_cm", "label", "nominal_cm", "ranges_cm"] {
        assert!(message.contains(word), "{word} missing from: {message}");
    }
    let text = GOOD.replace("gender: unisex,", "gender: unisex, colour: \"red\",");
    let message = load_str(&text).to_string();
    for word in ["colour", "name", "source", "primary", "sizes"] {
        assert!(message.contains(word), "{word} missing from: {message}");
    }
    let text = GOOD.replace("gender: unisex,", "gender: female_ish,");
    let message = load_str(&text).to_string();
    for word in ["female_ish", "female", "male", "unisex"] {
        assert!(message.contains(word), "{word} missing from: {message}");
    }
}

#[test]
fn unknown_measure_lists_the_known_measures() {
    let text = GOOD.replace(r#""waist": (70, 76)"#, r#""wasit": (70, 76)"#);
    let (p, message) = problem(&text);
    assert!(matches!(p, ChartProblem::UnknownMeasure { .. }));
    assert!(message.contains("size `M`, ranges_cm"), "{message}");
    assert!(message.contains("`wasit`"), "{message}");
    assert!(message.contains(&Measure::names()), "{message}");
}

#[test]
fn min_above_max_names_size_measure_and_range() {
    let text = GOOD.replace(r#""waist": (70, 76)"#, r#""waist": (76, 70)"#);
    let (p, message) = problem(&text);
    assert_eq!(
        p,
        ChartProblem::MinNotBelowMax {
            size: "M".into(),
            measure: Measure::Waist,
            min_cm: 76.0,
            max_cm: 70.0
        }
    );
    assert!(message.contains("size `M`, waist"), "{message}");
    assert!(message.contains("(76, 70)"), "{message}");
    assert!(message.contains("min < max"), "{message}");
}

#[test]
fn a_three_metre_waist_is_refused_with_the_accepted_range() {
    let text = GOOD.replace(r#""waist": (70, 76)"#, r#""waist": (70, 300)"#);
    let (p, message) = problem(&text);
    assert!(matches!(
        p,
        ChartProblem::Implausible {
            measure: Measure::Waist,
            field: "max",
            ..
        }
    ));
    assert!(message.contains("size `M`, waist: max 300 cm"), "{message}");
    assert!(message.contains("accepted 45 to 170 cm"), "{message}");
    // The same in a nominal table.
    let text = r#"(name: "t", gender: male, sizes: [
        (label: "1", nominal_cm: {"waist": 80}),
        (label: "2", nominal_cm: {"waist": 3000}),
    ])"#;
    let (_, message) = problem(text);
    assert!(
        message.contains("size `2`, waist: nominal value 3000 cm"),
        "{message}"
    );
}

#[test]
fn non_numbers_are_refused() {
    let text = GOOD.replace(r#""bust": (82, 88)"#, r#""bust": (NaN, 88)"#);
    let (p, message) = problem(&text);
    assert!(matches!(p, ChartProblem::NotFinite { .. }));
    assert!(message.contains("size `S`, bust: min is NaN"), "{message}");
    assert!(message.contains("accepted: 60 to 160 cm"), "{message}");
}

#[test]
fn sizes_out_of_order_are_refused() {
    let text = GOOD.replace(r#""bust": (88, 94)"#, r#""bust": (80, 86)"#);
    let (p, message) = problem(&text);
    assert!(matches!(
        p,
        ChartProblem::Unordered {
            measure: Measure::Bust,
            ..
        }
    ));
    assert!(
        message.contains("size `M` (80-86 cm) comes after size `S` (82-88 cm)"),
        "{message}"
    );
}

#[test]
fn other_content_errors() {
    let (p, _) = problem(r#"(name: "t", gender: male, sizes: [])"#);
    assert_eq!(p, ChartProblem::NoSizes);

    let (p, message) = problem(&GOOD.replace(r#"label: "M""#, r#"label: "S""#));
    assert!(matches!(p, ChartProblem::DuplicateLabel { .. }));
    assert!(message.contains("labelled `S`"), "{message}");

    let (p, _) = problem(&GOOD.replace(r#"label: "M""#, r#"label: " ""#));
    assert_eq!(p, ChartProblem::EmptyLabel { number: 2 });

    let (p, message) = problem(&GOOD.replace(
        r#""waist": (70, 76)"#,
        r#""waist": (70, 76), "waist": (71, 77)"#,
    ));
    assert!(matches!(p, ChartProblem::DuplicateMeasure { .. }));
    assert!(
        message.contains("size `M`: measure `waist` is given twice"),
        "{message}"
    );

    let (p, message) = problem(&GOOD.replace(
        r#"ranges_cm: {"bust": (88, 94), "waist": (70, 76)}"#,
        r#"ranges_cm: {"bust": (88, 94)}, nominal_cm: {"waist": 73}"#,
    ));
    assert!(matches!(p, ChartProblem::MixedForms { .. }));
    assert!(
        message.contains("waist is a nominal value in size `M`"),
        "{message}"
    );

    let (p, message) = problem(&GOOD.replace(r#"["bust"]"#, r#"["bust", "hip"]"#));
    assert_eq!(
        p,
        ChartProblem::PrimaryMissing {
            measure: Measure::Hip,
            size: "S".into()
        }
    );
    assert!(
        message.contains("primary measure hip is not given in size `S`"),
        "{message}"
    );

    let (p, _) = problem(&GOOD.replace(
        r#"(label: "M", ranges_cm: {"bust": (88, 94), "waist": (70, 76)})"#,
        r#"(label: "M")"#,
    ));
    assert_eq!(p, ChartProblem::NoMeasures { size: "M".into() });

    let (p, message) = problem(
        r#"(name: "t", gender: male, sizes: [
            (label: "1", nominal_cm: {"neck": 40}),
            (label: "2", nominal_cm: {"neck": 40}),
        ])"#,
    );
    assert!(matches!(p, ChartProblem::SingleNominal { .. }));
    assert!(message.contains("give `ranges_cm` for neck"), "{message}");
}

#[test]
fn a_malformed_file_on_disk_is_named_in_the_error() {
    let dir = std::env::temp_dir().join(format!("fitroom-sizing-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("broken.ron");
    std::fs::write(
        &path,
        GOOD.replace(r#""waist": (64, 70)"#, r#""waist": (70, 64)"#),
    )
    .unwrap();
    let result = SizeChart::load(&path);
    std::fs::remove_dir_all(&dir).unwrap();
    let message = result.expect_err("min > max must be refused").to_string();
    assert!(
        message.starts_with(&format!("{}: size `S`, waist", path.display())),
        "{message}"
    );

    let missing = chart_path("no-such-chart.ron");
    let message = SizeChart::load(&missing).unwrap_err().to_string();
    assert!(message.contains("no-such-chart.ron"), "{message}");
}
