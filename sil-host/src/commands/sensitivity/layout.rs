//! Where the markers of one row of a sensitivity panel go, so that no marker
//! hides another: markers of different groups (a series, or a case whose ideal
//! ring and sampled dot belong together) that would touch on the row are moved
//! apart vertically, each group to a sub-row of its own, symmetric about the row;
//! markers with room keep the row's line. A deterministic dodge: the same values
//! give the same picture.

/// A marker on a row: its group, its centre along the value axis and its
/// half-width, px.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mark {
    /// The marker's group (markers of one group may overlap: one glyph).
    pub group: usize,
    /// Its centre along the value axis, px.
    pub x_px: f64,
    /// Its half-width (outer radius), px.
    pub half_w: f64,
}

/// The vertical offset of each of `marks` from its row's line, px: 0 for a
/// marker that touches no marker of another group; else, for each cluster of
/// markers that touch (transitively), its groups in ascending order at
/// `(j - (m - 1) / 2) * pitch` for the `j`th of its `m` groups.
pub fn dodge(marks: &[Mark], pitch: f64) -> Vec<f64> {
    let n = marks.len();
    // Union-find over the pairs of markers closer than their half-widths and a pixel
    // (of one group too: a group's markers at one place share its sub-row).
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for a in 0..n {
        for b in a + 1..n {
            let (ma, mb) = (marks[a], marks[b]);
            if (ma.x_px - mb.x_px).abs() < ma.half_w + mb.half_w + 1.0 {
                let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
                parent[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    let roots: Vec<usize> = (0..n).map(|i| root(&mut parent, i)).collect();
    (0..n)
        .map(|i| {
            let mut groups: Vec<usize> = (0..n).filter(|&k| roots[k] == roots[i]).map(|k| marks[k].group).collect();
            groups.sort_unstable();
            groups.dedup();
            let j = groups.iter().position(|g| *g == marks[i].group).unwrap_or(0) as f64;
            (j - (groups.len() as f64 - 1.0) / 2.0) * pitch
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mark(group: usize, x_px: f64) -> Mark {
        Mark { group, x_px, half_w: 4.0 }
    }

    /// No two markers of different groups overlap after the dodge.
    fn apart(marks: &[Mark], dy: &[f64]) -> bool {
        marks.iter().zip(dy).enumerate().all(|(i, (a, ya))| {
            marks
                .iter()
                .zip(dy)
                .skip(i + 1)
                .all(|(b, yb)| a.group == b.group || (a.x_px - b.x_px).hypot(ya - yb) >= a.half_w + b.half_w - 1e-9)
        })
    }

    #[test]
    fn markers_with_room_keep_the_row_and_touching_ones_move_apart() {
        let marks = [mark(0, 10.0), mark(1, 100.0), mark(2, 104.0), mark(3, 109.0)];
        let dy = dodge(&marks, 9.0);
        assert_eq!(dy[0], 0.0, "alone on its stretch of the row");
        assert_eq!(&dy[1..], &[-9.0, 0.0, 9.0], "a cluster of three, by group, symmetric");
        assert!(apart(&marks, &dy));
    }

    #[test]
    fn one_groups_ring_and_dot_stay_together() {
        let marks = [
            Mark { group: 0, x_px: 50.0, half_w: 6.0 },
            Mark { group: 0, x_px: 50.5, half_w: 2.5 },
            Mark { group: 1, x_px: 55.0, half_w: 6.0 },
            Mark { group: 1, x_px: 55.0, half_w: 2.5 },
        ];
        let dy = dodge(&marks, 13.0);
        assert_eq!(dy, [-6.5, -6.5, 6.5, 6.5]);
        assert!(apart(&marks, &dy));
    }

    #[test]
    fn the_dodge_is_the_same_whatever_the_order_given() {
        let a = [mark(2, 30.0), mark(0, 33.0), mark(1, 80.0)];
        let b = [mark(1, 80.0), mark(0, 33.0), mark(2, 30.0)];
        let (da, db) = (dodge(&a, 9.0), dodge(&b, 9.0));
        assert_eq!((da[0], da[1], da[2]), (db[2], db[1], db[0]));
        assert_eq!(da[1], -4.5, "group 0 above group 2");
    }
}
