//! Malformed garment files are refused with the file, the line and the field named, and what
//! is accepted; never a panic.

mod common;

use fitroom_garment::{GarmentError, Pattern};

fn skirt_text() -> String {
    std::fs::read_to_string(common::garment_path("skirt")).expect("shipped")
}

/// Parses `text` as if it were `assets/garments/bad.ron` (so the fabric resolves) and returns
/// the error message.
fn error_of(text: &str) -> String {
    let dir = common::assets().join("garments");
    match Pattern::from_ron_str(text, "garments/bad.ron", &dir) {
        Ok(_) => panic!("accepted a malformed garment"),
        Err(e) => e.to_string(),
    }
}

/// The 1-based line of the first occurrence of `needle` in `text`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .expect("needle present")
        + 1
}

#[test]
fn the_shipped_skirt_parses_from_text() {
    let dir = common::assets().join("garments");
    Pattern::from_ron_str(&skirt_text(), "skirt.ron", &dir).expect("valid");
}

#[test]
fn errors_name_file_line_and_field() {
    let good = skirt_text();
    let cases: Vec<(String, &str, &str)> = vec![
        // (modified text, needle whose line the error must name, words the message must contain)
        (
            good.replace("(a: (\"front\", \"side_right\")", "(a: (\"frnt\", \"side_right\")"),
            "\"frnt\"",
            "seams[1].a|no panel \"frnt\"|the panels are: front, back",
        ),
        (
            good.replace("b: (\"back\", \"side_left\")", "b: (\"back\", \"side_lft\")"),
            "side_lft",
            "seams[0].b|no edge \"side_lft\"|its edges are",
        ),
        (
            good.replace("(panel: \"back\", edge: \"waist\"", "(panel: \"back\", edge: \"top\""),
            "edge: \"top\"",
            "attach[1]|no edge \"top\"",
        ),
        (good.replace("base_size: \"M\"", "base_size: \"XXL\""), "base_size", "base_size|\"XXL\" is not one of the sizes"),
        (good.replace("\"waist\": 70", "\"wasit\": 70"), "\"wasit\"", "sizes[1] (M)|unknown measure \"wasit\""),
        (good.replace("\"hip\": 100", "\"hip\": 1000"), "\"hip\": 1000", "sizes[2] (L)|hip is 1000 cm"),
        (good.replace("target_edge_cm: 2.5", "target_edge_cm: 0.01"), "target_edge_cm", "target_edge_cm|accepted 0.5..=20"),
        (good.replace("fabric: \"denim\"", "fabric: \"velvet\""), "fabric:", "fabric|velvet"),
        (good.replace("ease_cm: 1.0", "ease_cm: -3"), "ease_cm", "ease_cm|accepted 0..=30"),
        // Values of the wrong type: RON's message, and the field whose value it is.
        (good.replace("fabric: \"denim\"", "fabric: 12"), "fabric: 12", "in `fabric`: |string"),
        (
            good.replace("length_cm: 60", "length_cm: \"60\""),
            "length_cm: \"60\"",
            "in `sizes[1].length_cm`: ",
        ),
        (
            good.replace("\"hand_r\"]", "\"hand_rr\"]"),
            "\"hand_rr\"",
            "ignore_colliders[3]|no body collider \"hand_rr\"|the colliders are: upperarm_l",
        ),
        (
            good.replace("panels: [(\"front\", 0), (\"back\", 180)]", "panels: [(\"front\", 0)]"),
            "name: \"back\"",
            "(back)|is in no wrap",
        ),
        (
            // The front outline listed clockwise.
            good.replacen("(x: -30, y: -60, edge: \"hem\"),", "(x: -30, y: -60, edge: \"hem\"),\n                (x: -24.5, y: -19),\n                (x: -22.5, y: -8),\n                (x: -18, y: 0),\n                (x: 18, y: 0),\n                (x: 22.5, y: -8),\n                (x: 24.5, y: -19),\n                (x: 30, y: -60),\n            ],\n            outline_was: [", 1),
            "",
            "",
        ),
    ];
    for (k, (text, needle, words)) in cases.iter().enumerate() {
        if needle.is_empty() {
            // Unknown field `outline_was`: a syntax error with line and column.
            let msg = error_of(text);
            assert!(
                msg.starts_with("garments/bad.ron:") && msg.contains("outline_was"),
                "case {k}: {msg}"
            );
            continue;
        }
        let msg = error_of(text);
        let line = line_of(text, needle);
        assert!(
            msg.starts_with(&format!("garments/bad.ron:{line}:")),
            "case {k}: expected line {line}: {msg}"
        );
        for w in words.split('|') {
            assert!(msg.contains(w), "case {k}: `{w}` missing from: {msg}");
        }
    }
}

#[test]
fn geometry_errors_are_explained() {
    let good = skirt_text();
    // Clockwise outline.
    let cw = good.replacen(
        "(x: -30, y: -60, edge: \"hem\"),\n                (x: 30, y: -60, edge: \"side_left\"),\n                (x: 24.5, y: -19),\n                (x: 22.5, y: -8),\n                (x: 18, y: 0, edge: \"waist\"),\n                (x: -18, y: 0, edge: \"side_right\"),\n                (x: -22.5, y: -8),\n                (x: -24.5, y: -19),",
        "(x: -30, y: -60, edge: \"side_right\"),\n                (x: -24.5, y: -19),\n                (x: -22.5, y: -8),\n                (x: -18, y: 0, edge: \"waist\"),\n                (x: 18, y: 0, edge: \"side_left\"),\n                (x: 22.5, y: -8),\n                (x: 24.5, y: -19),\n                (x: 30, y: -60, edge: \"hem\"),",
        1,
    );
    assert_ne!(cw, good);
    let msg = error_of(&cw);
    assert!(
        msg.contains("clockwise") && msg.contains("panels[0] (front).outline"),
        "{msg}"
    );
    assert!(
        msg.starts_with(&format!("garments/bad.ron:{}:", line_of(&cw, "outline"))),
        "{msg}"
    );
    // Self-crossing outline (a bow tie).
    let bow = good.replacen("(x: 22.5, y: -8),", "(x: -40, y: -8),", 1);
    let msg = error_of(&bow);
    assert!(msg.contains("cross") || msg.contains("clockwise"), "{msg}");
    // An edge name used on two separate runs.
    let twice = good.replacen("(x: 22.5, y: -8),", "(x: 22.5, y: -8, edge: \"hem\"),", 1);
    let msg = error_of(&twice);
    assert!(
        msg.contains("\"hem\" is named on two separate runs"),
        "{msg}"
    );
    // Syntax errors carry line and column.
    let broken = good.replace("closed: true,", "closed: true");
    let msg = error_of(&broken);
    assert!(
        msg.starts_with(&format!(
            "garments/bad.ron:{}:",
            line_of(&broken, "closed: true") + 1
        )),
        "{msg}"
    );
    // A missing file.
    assert!(matches!(
        Pattern::load("/nonexistent/garment.ron"),
        Err(GarmentError::Read { .. })
    ));
}

#[test]
fn a_size_that_cannot_be_graded_is_refused() {
    // The skirt grades its length: every size needs `length_cm`.
    let text = skirt_text().replace(", length_cm: 62", "");
    let msg = error_of(&text);
    assert!(
        msg.contains("sizes (L)") && msg.contains("length_cm"),
        "{msg}"
    );
    assert!(
        msg.starts_with(&format!(
            "garments/bad.ron:{}:",
            line_of(&text, "label: \"L\"")
        )),
        "{msg}"
    );
    // Building a size the pattern does not have.
    let body = common::default_body();
    let err = common::pattern("skirt")
        .build(&body.surface, "XXS", &Default::default())
        .expect_err("no such size");
    assert!(err.to_string().contains("no size \"XXS\""), "{err}");
}
