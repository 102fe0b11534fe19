//! Order statistics shared by the workspace's crates.

/// The median of `values` (the mean of the two middle values for an even
/// count); `None` when empty. NaN sorts above every number
/// (`f64::total_cmp`). Reorders `values` (a partial selection, O(n)).
pub fn median(values: &mut [f64]) -> Option<f64> {
    let n = values.len();
    if n == 0 {
        return None;
    }
    let k = n / 2;
    let (below, mid, _) = values.select_nth_unstable_by(k, f64::total_cmp);
    let upper = *mid;
    if n % 2 == 1 {
        return Some(upper);
    }
    let lower = below.iter().copied().max_by(f64::total_cmp)?;
    Some(0.5 * (lower + upper))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_of_odd_even_and_empty_slices() {
        assert_eq!(median(&mut []), None);
        assert_eq!(median(&mut [3.0]), Some(3.0));
        assert_eq!(median(&mut [5.0, 1.0, 3.0]), Some(3.0));
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), Some(2.5));
        assert_eq!(median(&mut [2.0, -1.0]), Some(0.5));
        // NaN sorts last.
        assert_eq!(median(&mut [f64::NAN, 1.0, 2.0]), Some(2.0));
    }

    proptest::proptest! {
        #[test]
        fn the_median_is_the_middle_of_the_sorted_values(mut v in proptest::collection::vec(-1e6f64..1e6, 1..60)) {
            let mut s = v.clone();
            s.sort_by(f64::total_cmp);
            let n = s.len();
            let want = if n % 2 == 1 { s[n / 2] } else { 0.5 * (s[n / 2 - 1] + s[n / 2]) };
            proptest::prop_assert_eq!(median(&mut v), Some(want));
        }
    }
}
