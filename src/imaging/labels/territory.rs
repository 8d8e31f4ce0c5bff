//! The territory of every object: the samples nearer to it than to any other.

use super::{neighbours, Dims};
use std::collections::VecDeque;

/// Every sample's nearest object of `labels` in steps between face neighbours (a
/// breadth-first flood from every labelled sample at once; a sample as near to
/// two objects goes to the one that reached it first, the lower label at equal
/// distance in the samples' order). All 0 when `labels` has no object.
pub fn territories(labels: &[u32], dims: Dims) -> Vec<u32> {
    let mut out = labels.to_vec();
    let mut queue: VecDeque<usize> = (0..labels.len()).filter(|&p| labels[p] != 0).collect();
    let mut nb = Vec::with_capacity(6);
    while let Some(p) = queue.pop_front() {
        neighbours(dims, p, &mut nb);
        for &q in &nb {
            if out[q] == 0 {
                out[q] = out[p];
                queue.push_back(q);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two objects split a row between them at the middle; no object, no territory.
    #[test]
    fn the_samples_go_to_the_nearest_object() {
        let dims = [9, 1, 1];
        let labels = [1, 0, 0, 0, 0, 0, 0, 0, 2];
        assert_eq!(territories(&labels, dims), vec![1, 1, 1, 1, 1, 2, 2, 2, 2]);
        assert_eq!(territories(&[0; 9], dims), vec![0; 9]);
        let dims = [3, 3, 2];
        let mut labels = vec![0; 18];
        labels[0] = 3;
        assert!(territories(&labels, dims).iter().all(|&t| t == 3));
    }
}
