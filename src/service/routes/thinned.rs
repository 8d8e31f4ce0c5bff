//! At most a given number of many items, evenly spaced in their order, the
//! first and the last kept, in memory that does not grow with how many are seen:
//! the plot of a long history, the checkpoints evolution.glb shows.

/// Every `stride`-th item seen, the stride doubled (and every other item
/// dropped) whenever more than `most` are kept; the last item seen is kept too.
pub(super) struct Thinned<T> {
    items: Vec<T>,
    last: Option<T>,
    seen: usize,
    stride: usize,
    most: usize,
}

impl<T> Thinned<T> {
    /// At most `most` items (and the last one).
    pub(super) fn new(most: usize) -> Self {
        Thinned { items: Vec::new(), last: None, seen: 0, stride: 1, most: most.max(1) }
    }

    pub(super) fn push(&mut self, item: T) {
        let k = self.seen;
        self.seen += 1;
        if k % self.stride != 0 {
            self.last = Some(item);
            return;
        }
        self.last = None;
        self.items.push(item);
        if self.items.len() > self.most {
            // those at multiples of the doubled stride
            self.stride *= 2;
            let mut i = 0;
            self.items.retain(|_| {
                i += 1;
                (i - 1) % 2 == 0
            });
        }
    }

    /// The kept items in order, the last one seen at the end.
    pub(super) fn into_items(mut self) -> Vec<T> {
        self.items.extend(self.last);
        self.items
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_evenly_spaced_items_with_the_first_and_the_last() {
        let mut t = Thinned::new(100);
        (0..10_000).for_each(|k| t.push(k));
        let kept = t.into_items();
        assert!(kept.len() <= 101 && kept.len() > 50, "{}", kept.len());
        assert_eq!((kept[0], *kept.last().unwrap()), (0, 9_999));
        let gaps: Vec<i32> = kept.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(gaps[..gaps.len() - 1].iter().all(|&g| g == gaps[0]), "{gaps:?}");
        let mut few = Thinned::new(100);
        (0..7).for_each(|k| few.push(k));
        assert_eq!(few.into_items(), (0..7).collect::<Vec<_>>());
    }
}
