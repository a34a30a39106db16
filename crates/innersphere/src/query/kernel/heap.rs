//! A binary min-heap of node pairs keyed by f32, over a pre-reserved `Vec` (no allocation
//! once its capacity suffices; `clear` keeps the capacity).

/// A node pair with its priority.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Entry {
    pub key: f32,
    pub a: u32,
    pub b: u32,
    /// B's node centre in A's frame.
    pub c: [f32; 3],
}

/// Min-heap on `key` (ties in any order).
#[derive(Debug, Default)]
pub(crate) struct PairHeap {
    v: Vec<Entry>,
}

impl PairHeap {
    pub(crate) fn with_capacity(n: usize) -> Self {
        PairHeap {
            v: Vec::with_capacity(n),
        }
    }

    #[inline]
    pub(crate) fn clear(&mut self) {
        self.v.clear();
    }

    #[inline]
    pub(crate) fn len(&self) -> usize {
        self.v.len()
    }

    /// Entries in heap order (for sums over what is left).
    pub(crate) fn entries(&self) -> &[Entry] {
        &self.v
    }

    #[inline]
    pub(crate) fn push(&mut self, e: Entry) {
        let v = &mut self.v;
        let mut i = v.len();
        v.push(e);
        while i > 0 {
            let p = (i - 1) / 2;
            if v[p].key <= e.key {
                break;
            }
            v[i] = v[p];
            i = p;
        }
        v[i] = e;
    }

    #[inline]
    pub(crate) fn pop(&mut self) -> Option<Entry> {
        let v = &mut self.v;
        let last = v.pop()?;
        if v.is_empty() {
            return Some(last);
        }
        let top = v[0];
        let n = v.len();
        let mut i = 0;
        loop {
            let l = 2 * i + 1;
            if l >= n {
                break;
            }
            let r = l + 1;
            let c = if r < n && v[r].key < v[l].key { r } else { l };
            if last.key <= v[c].key {
                break;
            }
            v[i] = v[c];
            i = c;
        }
        v[i] = last;
        Some(top)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_in_order() {
        let mut h = PairHeap::with_capacity(4);
        let mut s = 7u32;
        let mut keys = Vec::new();
        for i in 0..500 {
            s = s.wrapping_mul(1103515245).wrapping_add(12345);
            let k = (s >> 8) as f32 / 1000.0;
            keys.push(k);
            h.push(Entry {
                key: k,
                a: i,
                b: 0,
                c: [0.0; 3],
            });
        }
        keys.sort_by(f32::total_cmp);
        for k in keys {
            assert_eq!(h.pop().unwrap().key, k);
        }
        assert!(h.pop().is_none());
        assert_eq!(h.len(), 0);
    }
}
