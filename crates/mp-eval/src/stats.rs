//! Summary statistics of the evaluations.

use std::borrow::Borrow;

/// The mean of the finite values (NaN and ±∞ left out); NaN when there is none.
pub fn mean<I>(values: I) -> f64
where
    I: IntoIterator,
    I::Item: Borrow<f64>,
{
    let (s, n) = values
        .into_iter()
        .map(|x| *x.borrow())
        .filter(|x| x.is_finite())
        .fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    if n == 0 {
        f64::NAN
    } else {
        s / n as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn means_leave_out_what_is_not_finite() {
        assert_eq!(mean([1.0, 2.0, 6.0]), 3.0);
        let values = vec![1.0, f64::NAN, 3.0];
        assert_eq!(mean(&values), 2.0);
        assert_eq!(mean([f64::INFINITY, 4.0].iter()), 4.0);
        assert!(mean(Vec::<f64>::new()).is_nan());
    }
}
