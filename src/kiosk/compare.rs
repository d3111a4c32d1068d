//! Two sizes side by side: while [`TryOn::compare`] is on, the avatar's twin
//! ([`fitroom_body::twin`]) stands beside it wearing the garment's next size up (the next down
//! when the avatar wears the largest), and the camera frames both. The twin's size follows
//! the avatar's: size up, size down and another garment move it along.

use bevy::prelude::*;
use fitroom_body::twin::TwinAvatar;
use fitroom_garment::asset::GarmentAsset;
use fitroom_garment::plugin::{GarmentRequest, GarmentStatus};

use super::KioskState;
use super::actions::{TryOn, garment_sizes, size_worn};

/// Where the twin stands: beside the avatar (world +x; on the screen's left in the mirror),
/// far enough apart that the widest dress does not touch.
pub const TWIN_OFFSET: Vec3 = Vec3::new(0.8, 0.0, 0.0);

/// The size beside `worn` among `sizes` (smallest first): the next up, or the next down for the
/// largest; `None` for a garment of one size or a size not in the list.
pub fn neighbour_size(sizes: &[String], worn: &str) -> Option<String> {
    let at = sizes.iter().position(|s| s == worn)?;
    let other = if at + 1 < sizes.len() {
        at + 1
    } else {
        at.checked_sub(1)?
    };
    sizes.get(other).cloned()
}

/// Keeps the twin and its size in step with [`TryOn::compare`] and the size worn (after the
/// actions are applied).
pub(super) fn follow_compare(
    mut commands: Commands,
    state: Res<State<KioskState>>,
    mut tryon: ResMut<TryOn>,
    twin: Option<Res<TwinAvatar>>,
    mut request: ResMut<GarmentRequest>,
    status: Res<GarmentStatus>,
    garments: Res<Assets<GarmentAsset>>,
) {
    if *state.get() != KioskState::TryOn {
        // A new person starts with one avatar.
        tryon.compare = false;
    }
    let wanted = if tryon.compare && request.path.is_some() {
        let sizes = garment_sizes(&status, &garments);
        size_worn(&request, &status).and_then(|w| neighbour_size(&sizes, &w))
    } else {
        None
    };
    // Before the garment's sizes are known the twin waits (it appears with its size).
    let show = tryon.compare && (wanted.is_some() || request.compare.is_some());
    match (show, twin.is_some()) {
        (true, false) => commands.insert_resource(TwinAvatar {
            offset: TWIN_OFFSET,
        }),
        (false, true) => commands.remove_resource::<TwinAvatar>(),
        _ => {}
    }
    let keep = if tryon.compare && wanted.is_none() {
        // Sizes not known yet (a garment loading): the twin keeps its size until they are.
        request.compare.clone()
    } else {
        wanted
    };
    if request.compare != keep {
        request.compare = keep;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_twin_wears_the_next_size_up_or_down_from_the_largest() {
        let sizes: Vec<String> = ["S", "M", "L"].map(String::from).to_vec();
        assert_eq!(neighbour_size(&sizes, "S").as_deref(), Some("M"));
        assert_eq!(neighbour_size(&sizes, "M").as_deref(), Some("L"));
        assert_eq!(neighbour_size(&sizes, "L").as_deref(), Some("M"));
        assert_eq!(neighbour_size(&sizes, "XL"), None);
        assert_eq!(neighbour_size(&["M".to_string()], "M"), None);
    }
}
