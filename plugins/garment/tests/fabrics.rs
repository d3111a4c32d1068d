//! The shipped fabric files load, carry their sources, and malformed fabric files are refused
//! with the file, the line and the field.

mod common;

use fitroom_garment::fabric::FIELD_RANGES;
use fitroom_garment::{FabricSpec, GarmentError, load_fabric};

#[test]
fn every_shipped_fabric_loads_in_physical_ranges() {
    for name in common::FABRICS {
        let path = common::assets().join("fabrics").join(format!("{name}.ron"));
        let spec = FabricSpec::load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert!(!spec.sources.is_empty(), "{name}: sources are listed");
        let f = spec.fabric;
        f.validate().expect("valid for the cloth core");
        // Real garment fabrics: 30 g/m² to 1 kg/m².
        assert!(
            (0.03..=1.0).contains(&f.areal_density_kg_m2),
            "{name}: {f:?}"
        );
        assert!(
            f.stretch_stiffness_n_m > 10.0 * f.shear_stiffness_n_m,
            "{name}: stretch >> shear"
        );
        assert_eq!(load_fabric(&path).expect("loads"), f);
    }
    // Heavier fabrics bend harder: silk < cotton < denim < leather.
    let bend = |n: &str| {
        load_fabric(common::assets().join(format!("fabrics/{n}.ron")))
            .expect("loads")
            .bend_stiffness_n_m
    };
    assert!(
        bend("silk") < bend("cotton")
            && bend("cotton") < bend("denim")
            && bend("denim") < bend("leather")
    );
}

const GOOD: &str = "Fabric(
    name: \"test cloth\",
    areal_density_kg_m2: 0.15,
    stretch_stiffness_n_m: 2000,
    shear_stiffness_n_m: 100,
    bend_stiffness_n_m: 2e-5,
    damping_per_s: 0.3,
    friction: 0.4,
    drag_coefficient: 1.0,
    lift_coefficient: 0.3,
)";

fn error_of(text: &str) -> String {
    match FabricSpec::from_ron_str(text, "fabrics/bad.ron") {
        Ok(spec) => panic!("accepted a bad fabric: {spec:?}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn out_of_range_values_name_file_line_field_and_range() {
    for (field, min, max, _) in FIELD_RANGES {
        let line = GOOD
            .lines()
            .position(|l| l.contains(field))
            .expect("field in GOOD")
            + 1;
        let value = GOOD
            .lines()
            .nth(line - 1)
            .and_then(|l| l.split(':').nth(1))
            .expect("value");
        let value = value.trim().trim_end_matches(',');
        for bad in [
            format!("{}", max * 10.0 + 1.0),
            "-1".to_owned(),
            "NaN".to_owned(),
        ] {
            if bad == "-1" && min < 0.0 {
                continue;
            }
            let text = GOOD.replace(&format!("{field}: {value}"), &format!("{field}: {bad}"));
            let msg = error_of(&text);
            assert!(
                msg.starts_with(&format!("fabrics/bad.ron:{line}:")),
                "{msg}"
            );
            assert!(msg.contains(field), "{msg}");
            assert!(msg.contains("accepted range"), "{msg}");
        }
    }
    // A density typed in g/m² is caught.
    let msg = error_of(&GOOD.replace("0.15", "150"));
    assert!(
        msg.contains("areal_density_kg_m2") && msg.contains("kg/m²"),
        "{msg}"
    );
}

#[test]
fn syntax_unknown_and_missing_fields_are_located() {
    let msg = error_of(&GOOD.replace("damping_per_s: 0.3,", "damping_per_s: 0.3"));
    assert!(
        msg.starts_with("fabrics/bad.ron:8:"),
        "missing comma: {msg}"
    );
    let msg = error_of(&GOOD.replace("friction: 0.4,", "friction: 0.4,\n    frcition: 0.4,"));
    assert!(
        msg.starts_with("fabrics/bad.ron:9:") && msg.contains("frcition"),
        "unknown field: {msg}"
    );
    let msg = error_of(&GOOD.replace("friction: 0.4,", "friction: \"high\","));
    assert!(
        msg.starts_with("fabrics/bad.ron:8:") && msg.contains("in `friction`: "),
        "a value of the wrong type: {msg}"
    );
    let msg = error_of(&GOOD.replace("    lift_coefficient: 0.3,\n", ""));
    assert!(msg.contains("lift_coefficient"), "missing field: {msg}");
    let msg = error_of(&GOOD.replace("\"test cloth\"", "\"\""));
    assert!(
        msg.starts_with("fabrics/bad.ron:2:") && msg.contains("name"),
        "{msg}"
    );
    assert!(matches!(
        FabricSpec::load("/nonexistent/fabric.ron"),
        Err(GarmentError::Read { .. })
    ));
}
