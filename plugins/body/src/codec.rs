//! Serde encodings that make morph targets compress well (used by `.fitbody`).
//!
//! Morph target entries are sorted by vertex and neighbouring vertices move alike, so the
//! indices are stored as gaps and each displacement component as the difference from the
//! previous entry. Both are exact (wrapping arithmetic) and leave the in-memory types alone.

/// `Vec<u32>` of increasing indices as `[first, second - first, ...]` (wrapping).
pub mod index_gaps {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(indices: &[u32], s: S) -> Result<S::Ok, S::Error> {
        let mut prev = 0u32;
        let gaps: Vec<u32> = indices
            .iter()
            .map(|&i| {
                let g = i.wrapping_sub(prev);
                prev = i;
                g
            })
            .collect();
        gaps.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<u32>, D::Error> {
        let gaps = Vec::<u32>::deserialize(d)?;
        let mut prev = 0u32;
        Ok(gaps
            .into_iter()
            .map(|g| {
                prev = prev.wrapping_add(g);
                prev
            })
            .collect())
    }
}

/// `Vec<[i16; 3]>` as three planes (x, y, z), each `[v0, v1 - v0, ...]` (wrapping `i16`).
pub mod planar_differences {
    use serde::de::Error;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(deltas: &[[i16; 3]], s: S) -> Result<S::Ok, S::Error> {
        let mut planes: [Vec<i16>; 3] = Default::default();
        for (c, plane) in planes.iter_mut().enumerate() {
            let mut prev = 0i16;
            plane.extend(deltas.iter().map(|d| {
                let v = d[c].wrapping_sub(prev);
                prev = d[c];
                v
            }));
        }
        planes.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<[i16; 3]>, D::Error> {
        let planes = <[Vec<i16>; 3]>::deserialize(d)?;
        let n = planes[0].len();
        if planes[1].len() != n || planes[2].len() != n {
            return Err(D::Error::custom(format!(
                "delta planes have different lengths ({}, {}, {})",
                n,
                planes[1].len(),
                planes[2].len()
            )));
        }
        let mut out = vec![[0i16; 3]; n];
        for (c, plane) in planes.iter().enumerate() {
            let mut prev = 0i16;
            for (o, &v) in out.iter_mut().zip(plane) {
                prev = prev.wrapping_add(v);
                o[c] = prev;
            }
        }
        Ok(out)
    }
}
