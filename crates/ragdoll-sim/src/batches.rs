//! Dealing islands to threads: consecutive islands grouped into batches of about equal
//! work, the unit both methods hand to rayon (`particle::islands`, `rigid::parallel`).
//! Few batches per thread spare gathering each island into arrays of its own; enough
//! of them let work stealing even out their unequal cost.

/// Deals islands, in order, into about `wanted` runs of consecutive islands of about
/// equal work (`work[i]`, island `i`'s): each island's batch, numbered densely from 0.
/// A batch ends where the work before an island crosses the next multiple of
/// total / `wanted`; an island larger than a share makes one batch, not empty ones
/// after it.
pub(crate) fn deal(work: &[usize], wanted: usize) -> Vec<u32> {
    let total: usize = work.iter().sum();
    let (mut batch, mut done, mut last_cut) = (0u32, 0usize, None);
    work.iter()
        .map(|&w| {
            let cut = done * wanted / total.max(1);
            if last_cut.is_some_and(|c| c != cut) {
                batch += 1;
            }
            last_cut = Some(cut);
            done += w;
            batch
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::deal;

    /// Consecutive islands share a batch until the work before an island crosses the
    /// next multiple of total / wanted; batches are numbered densely (a large island
    /// that spans several shares makes one batch, not empty ones after it).
    #[test]
    fn batches_deal_consecutive_islands_by_work() {
        assert_eq!(deal(&[5, 5, 5, 5], 2), [0, 0, 1, 1]);
        assert_eq!(deal(&[1, 1, 30, 1, 1], 4), [0, 0, 0, 1, 1]);
        assert_eq!(deal(&[3, 3, 3], 8), [0, 1, 2]);
        assert_eq!(deal(&[7], 4), [0]);
    }
}
