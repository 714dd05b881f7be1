//! A hashed uniform grid of points for fixed-radius queries: the photon mappers' search
//! structure (SPPM's visible points, VCM's light vertices).

use pt_math::Vec3;

/// A uniform grid of cells of edge `2 r`, hashed into buckets, holding items at points: each
/// item is stored once, in its point's cell, and a query visits the cells (at most 2 per axis)
/// that the ball of radius r about it overlaps. Items are stored bucket by bucket, so the
/// items near a query lie in a few contiguous runs of memory.
pub(crate) struct PointGrid<T> {
    cell: f32,
    r: f32,
    /// Per bucket, the range of `entries` it holds.
    starts: Vec<u32>,
    /// Items with their points, bucket by bucket, in the order given within a bucket.
    entries: Vec<(Vec3, T)>,
}

impl<T: Copy> PointGrid<T> {
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

    /// The grid of `items` (at their points) for queries within the radius `r`: a counting
    /// sort into buckets.
    pub(crate) fn new(items: Vec<(Vec3, T)>, r: f32) -> PointGrid<T> {
        let buckets = (2 * items.len()).max(1);
        let mut g = PointGrid {
            cell: 2.0 * r,
            r,
            starts: vec![0; buckets + 1],
            entries: Vec::new(),
        };
        let keys: Vec<u32> = items
            .iter()
            .map(|(p, _)| g.bucket(g.cell_of(*p)) as u32)
            .collect();
        for &b in &keys {
            g.starts[b as usize + 1] += 1;
        }
        for b in 0..buckets {
            g.starts[b + 1] += g.starts[b];
        }
        let mut fill = g.starts.clone();
        let mut slots: Vec<Option<(Vec3, T)>> = vec![None; items.len()];
        for (item, &b) in items.into_iter().zip(&keys) {
            slots[fill[b as usize] as usize] = Some(item);
            fill[b as usize] += 1;
        }
        g.entries = slots.into_iter().flatten().collect();
        g
    }

    /// The items whose points lie within the radius of `p` (closed ball): bucket by bucket,
    /// in the order given within each.
    #[inline]
    pub(crate) fn within(&self, p: Vec3, mut visit: impl FnMut(&T)) {
        let r = Vec3::splat(self.r);
        let (lo, hi) = (self.cell_of(p - r), self.cell_of(p + r));
        let mut seen = [usize::MAX; 27];
        let mut n = 0;
        let r2 = self.r * self.r;
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let b = self.bucket([x, y, z]);
                    // Two cells may share a bucket: visit it once.
                    if seen[..n].contains(&b) {
                        continue;
                    }
                    if n < seen.len() {
                        seen[n] = b;
                        n += 1;
                    }
                    for (q, item) in
                        &self.entries[self.starts[b] as usize..self.starts[b + 1] as usize]
                    {
                        if (*q - p).length_squared() <= r2 {
                            visit(item);
                        }
                    }
                }
            }
        }
    }
}
