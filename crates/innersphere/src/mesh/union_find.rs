//! Union-find over indices: the connected parts of a mesh (components, contact spots, vertices
//! on one side of a surface), and the connected pieces of two meshes' overlap.

/// Disjoint sets of `0..n`; a set's root is its smallest member, so the roots (and what is
/// counted by them) do not depend on the order of the unions.
#[derive(Debug, Clone, Default)]
pub struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    /// `n` singletons.
    pub fn new(n: usize) -> UnionFind {
        UnionFind {
            parent: (0..n as u32).collect(),
        }
    }

    /// No sets (the memory kept, for [`push`](Self::push) to refill without allocating).
    pub fn clear(&mut self) {
        self.parent.clear();
    }

    /// A new singleton set; returns its member.
    pub fn push(&mut self) -> u32 {
        let v = self.parent.len() as u32;
        self.parent.push(v);
        v
    }

    /// The root of `v`'s set (with path halving).
    pub fn find(&mut self, mut v: u32) -> u32 {
        let p = &mut self.parent;
        while p[v as usize] != v {
            let g = p[p[v as usize] as usize];
            p[v as usize] = g;
            v = g;
        }
        v
    }

    /// Joins the sets of `u` and `v`; returns the root of the union.
    pub fn union(&mut self, u: u32, v: u32) -> u32 {
        let (ru, rv) = (self.find(u), self.find(v));
        let (lo, hi) = (ru.min(rv), ru.max(rv));
        self.parent[hi as usize] = lo;
        lo
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_are_the_smallest_members() {
        let mut u = UnionFind::new(6);
        u.union(4, 2);
        u.union(5, 4);
        u.union(1, 3);
        assert_eq!(
            (0..6).map(|v| u.find(v)).collect::<Vec<_>>(),
            [0, 1, 2, 1, 2, 2]
        );
        assert_eq!(u.union(3, 5), 1);
        assert_eq!(u.find(5), 1);
        // Grown one at a time after a clear: the same sets.
        u.clear();
        for v in 0..6 {
            assert_eq!(u.push(), v);
        }
        u.union(4, 2);
        assert_eq!(u.find(4), 2);
        assert_eq!(u.find(5), 5);
    }
}
