//! Order statistics shared by every host module: one median.

/// The median of the finite values of `values` (NaN and infinities are left out); the mean of the
/// middle pair for an even count; NaN when no value is finite.
///
/// ```
/// use accelcal_host::stats::median;
/// assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
/// assert_eq!(median(&[4.0, 1.0, f64::NAN, 2.0, 3.0]), 2.5);
/// assert!(median(&[f64::NAN]).is_nan());
/// ```
pub fn median(values: &[f64]) -> f64 {
    let mut finite: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if finite.is_empty() {
        return f64::NAN;
    }
    let n = finite.len();
    let (below, upper, _) = finite.select_nth_unstable_by(n / 2, f64::total_cmp);
    let upper = *upper;
    if n % 2 == 1 {
        return upper;
    }
    // The lower middle value is the largest of the half below the upper one.
    let lower = below.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    0.5 * (lower + upper)
}

#[cfg(test)]
mod tests {
    use super::median;

    #[test]
    fn odd_even_and_unsorted_counts() {
        assert_eq!(median(&[5.0]), 5.0);
        assert_eq!(median(&[9.0, -1.0, 4.0]), 4.0);
        assert_eq!(median(&[9.0, -1.0, 4.0, 7.0]), 5.5);
        assert_eq!(median(&[2.0, 2.0, 2.0, 1.0]), 2.0);
        let many: Vec<f64> = (0..1001).map(|i| f64::from((i * 7919) % 1001)).collect();
        assert_eq!(median(&many), 500.0);
    }

    #[test]
    fn non_finite_values_are_left_out_and_nothing_finite_is_nan() {
        assert_eq!(median(&[f64::INFINITY, 1.0, f64::NAN, 3.0, f64::NEG_INFINITY]), 2.0);
        assert!(median(&[]).is_nan());
        assert!(median(&[f64::NAN, f64::INFINITY]).is_nan());
    }
}
