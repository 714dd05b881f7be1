//! A hashed uniform grid of points for fixed-radius queries: the photon mappers' search
//! structure (SPPM's visible points, VCM's light vertices).

use pt_math::Vec3;

/// A uniform grid of cells of edge `2 r` hashed into buckets: every point is listed in each
/// cell its ball's bounding box overlaps (at most 8), so a query looks in its own cell only.
pub(crate) struct PointGrid {
    cell: f32,
    /// Per bucket, the range of `entries` it holds.
    starts: Vec<u32>,
    /// Point indices, bucket by bucket.
    entries: Vec<u32>,
}

impl PointGrid {
    fn bucket(&self, c: [i32; 3]) -> usize {
        // Teschner et al. 2003's spatial hash.
        let h = (c[0] as u32).wrapping_mul(73_856_093)
            ^ (c[1] as u32).wrapping_mul(19_349_663)
            ^ (c[2] as u32).wrapping_mul(83_492_791);
        h as usize % (self.starts.len() - 1)
    }

    fn cell_of(&self, p: Vec3) -> [i32; 3] {
        let q = p / self.cell;
        [q.x.floor() as i32, q.y.floor() as i32, q.z.floor() as i32]
    }

    /// The grid of `points` (indexed in their order) for queries within the radius `r`.
    pub(crate) fn new(points: impl ExactSizeIterator<Item = Vec3>, r: f32) -> PointGrid {
        let buckets = (2 * points.len()).max(1);
        let mut g = PointGrid {
            cell: 2.0 * r,
            starts: vec![0; buckets + 1],
            entries: Vec::new(),
        };
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(points.len() * 2);
        for (i, p) in points.enumerate() {
            let (lo, hi) = (g.cell_of(p - Vec3::splat(r)), g.cell_of(p + Vec3::splat(r)));
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        pairs.push((g.bucket([x, y, z]) as u32, i as u32));
                    }
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        for &(b, _) in &pairs {
            g.starts[b as usize + 1] += 1;
        }
        for b in 0..buckets {
            g.starts[b + 1] += g.starts[b];
        }
        g.entries = pairs.into_iter().map(|(_, i)| i).collect();
        g
    }

    /// The indices of the points that may lie within `r` of `p` (a superset: the caller
    /// tests the distance).
    pub(crate) fn near(&self, p: Vec3) -> &[u32] {
        let b = self.bucket(self.cell_of(p));
        &self.entries[self.starts[b] as usize..self.starts[b + 1] as usize]
    }
}
