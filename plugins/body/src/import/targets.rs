//! The MakeHuman morph targets the body keeps (macro, `measure-*` and region scale targets), read
//! from their `.target.gz` files and stored sparse, quantised to `i16` with a per-target scale (the
//! `.fitbody` layout of the crate docs).

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::{DECIMETRE, ImportError, ImportReport, parse_f32, read_gz, syntax};
use crate::model::MorphTarget;

/// Whether a target is one of the body-region scale targets that help fitting
/// (`neck/neck-scale-horiz-decr`, `legs/l-upperleg-scale-depth-incr`, ...): the `*-scale-*`
/// targets of the neck, torso, hip, legs and arms (not the face's or the feet's).
fn is_region_scale(root: &Path, dir: &Path, stem: &str) -> bool {
    let top = dir
        .strip_prefix(root)
        .ok()
        .and_then(|p| p.components().next())
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .unwrap_or_default();
    matches!(top.as_str(), "neck" | "torso" | "hip" | "legs" | "arms")
        && stem.contains("-scale-")
        && (stem.ends_with("-decr") || stem.ends_with("-incr"))
        && !stem.contains("foot")
        && !stem.contains("hand")
}

/// Collects `(name, path)` of the targets to import: everything under `macrodetails/`, every
/// `measure-*` target anywhere and the region scale targets ([`is_region_scale`]).
pub(super) fn collect_targets(
    root: &Path,
    dir: &Path,
    in_macrodetails: bool,
    out: &mut Vec<(String, PathBuf)>,
) -> Result<(), ImportError> {
    let io = |source| ImportError::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut entries: Vec<PathBuf> = fs::read_dir(dir)
        .map_err(io)?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()
        .map_err(io)?;
    entries.sort();
    for path in entries {
        let file_name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default()
            .to_string();
        if path.is_dir() {
            let macro_dir = in_macrodetails || (dir == root && file_name == "macrodetails");
            collect_targets(root, &path, macro_dir, out)?;
        } else if let Some(stem) = file_name.strip_suffix(".target.gz")
            && (in_macrodetails || stem.starts_with("measure-") || is_region_scale(root, dir, stem))
        {
            let rel = path.strip_prefix(root).unwrap_or(&path);
            let mut name: Vec<String> = rel
                .parent()
                .map(|p| {
                    p.components()
                        .map(|c| c.as_os_str().to_string_lossy().into_owned())
                        .collect()
                })
                .unwrap_or_default();
            name.push(stem.to_string());
            out.push((name.join("/"), path));
        }
    }
    Ok(())
}

/// Reads one `.target.gz` (lines `vertex dx dy dz` in decimetres, `#` comments) into a
/// quantised sparse target.
pub(super) fn parse_target(
    path: &Path,
    name: &str,
    vertex_count: usize,
    report: &mut ImportReport,
) -> Result<MorphTarget, ImportError> {
    let bytes = read_gz(path)?;
    let text = String::from_utf8(bytes).map_err(|e| ImportError::Invalid {
        path: path.to_path_buf(),
        field: "text".into(),
        message: format!("not UTF-8: {e}"),
    })?;
    let mut entries: BTreeMap<u32, Vec3> = BTreeMap::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let s = raw.trim();
        if s.is_empty() || s.starts_with('#') {
            continue;
        }
        let mut it = s.split_whitespace();
        let index_str = it.next().unwrap_or("");
        let index: u32 = index_str.parse().map_err(|_| {
            syntax(
                path,
                line,
                format!("vertex index '{index_str}' is not an integer"),
            )
        })?;
        if index as usize >= vertex_count {
            return Err(syntax(
                path,
                line,
                format!("vertex index {index} is past the {vertex_count} vertices of the mesh"),
            ));
        }
        let dx = parse_f32(path, line, "dx", it.next())?;
        let dy = parse_f32(path, line, "dy", it.next())?;
        let dz = parse_f32(path, line, "dz", it.next())?;
        if it.next().is_some() {
            return Err(syntax(path, line, "more than 4 fields (vertex dx dy dz)"));
        }
        let d = Vec3::new(dx, dy, dz);
        if d == Vec3::ZERO {
            report.zero_deltas_dropped += 1;
            continue;
        }
        // A vertex listed twice moves by the sum.
        *entries.entry(index).or_insert(Vec3::ZERO) += d * DECIMETRE;
    }
    Ok(quantise(name, &entries, report))
}

/// Quantises displacements (metres) to `i16` with `scale = max |component| / 32767`.
fn quantise(name: &str, entries: &BTreeMap<u32, Vec3>, report: &mut ImportReport) -> MorphTarget {
    let max = entries
        .values()
        .map(|d| d.abs().max_element())
        .fold(0.0f32, f32::max);
    let scale = max / i16::MAX as f32;
    let mut indices = Vec::with_capacity(entries.len());
    let mut deltas = Vec::with_capacity(entries.len());
    if scale > 0.0 {
        for (&i, &d) in entries {
            let q = (d / scale).round().clamp(
                Vec3::splat(-(i16::MAX as f32)),
                Vec3::splat(i16::MAX as f32),
            );
            let q = [q.x as i16, q.y as i16, q.z as i16];
            if q == [0, 0, 0] {
                report.quantised_to_zero_dropped += 1;
                continue;
            }
            indices.push(i);
            deltas.push(q);
        }
    }
    MorphTarget {
        name: name.to_string(),
        indices,
        deltas,
        scale_m: scale,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantisation_keeps_the_largest_exact_and_drops_zeroes() {
        let mut report = ImportReport::default();
        let mut e = BTreeMap::new();
        e.insert(3, Vec3::new(0.1, -0.05, 0.0));
        e.insert(7, Vec3::new(1e-9, 0.0, 0.0));
        let t = quantise("t", &e, &mut report);
        assert_eq!(t.indices, vec![3]);
        assert_eq!(t.deltas[0][0], i16::MAX);
        assert!((t.deltas[0][1] as f32 * t.scale_m + 0.05).abs() <= 0.51 * t.scale_m);
        assert_eq!(report.quantised_to_zero_dropped, 1);
    }
}
