//! The blow-up guard reports non-finite and absurd states, and `reset_to` recovers.

mod common;

use common::*;
use fitroom_cloth::{BlowUp, Fabric, Health};
use glam::Vec3A;

#[test]
fn an_injected_nan_is_reported_and_reset_restores_a_finite_state() {
    let (mesh, pins) = hanging_cloth(1.0, 20, 1.5);
    let mut cloth = solver(&mesh, Fabric::cotton(), &pins, settings(2));
    for _ in 0..30 {
        assert!(cloth.step(DT).unwrap().is_healthy());
    }
    cloth.positions_mut()[200] = Vec3A::new(f32::NAN, 0.0, 0.0);
    let report = cloth.step(DT).unwrap();
    assert!(
        matches!(report.health, Health::BlownUp(BlowUp::NonFinite { .. })),
        "{report:?}"
    );
    assert!(report.max_speed_m_s.is_nan());

    cloth.reset_to(mesh.positions()).unwrap();
    assert!(all_finite(cloth.positions()));
    assert!(cloth.velocities().iter().all(|v| *v == Vec3A::ZERO));
    for _ in 0..30 {
        let report = cloth.step(DT).unwrap();
        assert!(report.is_healthy(), "{report:?}");
    }
    assert!(all_finite(cloth.positions()));
}

#[test]
fn an_absurd_jump_is_reported() {
    let (mesh, pins) = hanging_cloth(1.0, 20, 1.5);
    let mut cloth = solver(&mesh, Fabric::cotton(), &pins, settings(1));
    cloth.step(DT).unwrap();
    // A particle thrown 50 m away: too fast or too stretched, either way not healthy.
    cloth.positions_mut()[300] += Vec3A::new(0.0, 0.0, 50.0);
    let report = cloth.step(DT).unwrap();
    assert!(
        matches!(
            report.health,
            Health::BlownUp(BlowUp::Speed { .. } | BlowUp::Stretch { .. })
        ),
        "{report:?}"
    );
}

#[test]
fn bad_inputs_are_refused_with_errors() {
    let (mesh, pins) = hanging_cloth(1.0, 4, 1.5);
    let mut cloth = solver(&mesh, Fabric::cotton(), &pins, settings(1));
    assert!(cloth.reset_to(&mesh.positions()[1..]).is_err());
    assert!(cloth.set_attachment_targets(&[glam::Vec3::ZERO]).is_err());
    assert!(
        cloth
            .set_attachment_targets(&[glam::Vec3::NAN, glam::Vec3::ZERO])
            .is_err()
    );
    assert!(cloth.set_colliders(&[], &[[0, 1]]).is_err());
    assert!(cloth.step(0.0).is_err());
    assert!(cloth.step(f32::NAN).is_err());
    assert!(
        fitroom_cloth::ClothSolver::new(&mesh, Fabric::cotton(), &[0, 0], settings(1)).is_err()
    );
    assert!(fitroom_cloth::ClothSolver::new(&mesh, Fabric::cotton(), &[99], settings(1)).is_err());
}

#[test]
fn a_stretch_below_the_guards_ratio_is_not_a_blow_up() {
    // The two top corners of a hanging cloth pulled apart slowly (0.6 m/s, so that nothing is
    // fast): its edges stretch through 4 (the guard's old threshold, which a pinched T-shirt
    // reaches and recovers from) to past 6 (the default).
    let (mesh, pins) = hanging_cloth(1.0, 4, 1.5);
    let mut cloth = solver(&mesh, Fabric::cotton(), &pins, settings(1));
    let guard = cloth.settings().guard;
    assert_eq!(guard.max_stretch_ratio, 6.0);
    let corners = pins.map(|v| mesh.positions()[v as usize]);
    let (mut between, mut past) = (0, 0);
    for k in 1..=1200 {
        let pull = 0.6 * k as f32 * DT;
        let targets = [
            corners[0] - glam::Vec3::X * pull,
            corners[1] + glam::Vec3::X * pull,
        ];
        cloth.set_attachment_targets(&targets).unwrap();
        let report = cloth.step(DT).unwrap();
        let ratio = report.max_stretch_ratio;
        if k % 60 == 0 {
            println!("{k}: ratio {ratio:.2}, {:?}", report.health);
        }
        assert!(report.max_speed_m_s < guard.max_speed_m_s, "{report:?}");
        if ratio <= guard.max_stretch_ratio {
            assert!(report.is_healthy(), "ratio {ratio}: {report:?}");
            between += usize::from(ratio > 4.0);
        } else {
            assert!(
                matches!(report.health, Health::BlownUp(BlowUp::Stretch { .. })),
                "ratio {ratio}: {report:?}"
            );
            past += 1;
            break;
        }
    }
    assert!(between > 10, "{between} steps between 4 and 6");
    assert_eq!(past, 1, "the pull reaches past the guard's ratio");
}
