//! Choosing which output frames a view or plot keeps.

/// `n` indices spread evenly over `0..m`, always including `0` and `m − 1`;
/// all of `0..m` when `n ≥ m`. Strictly increasing. Index `k` is
/// `round(k (m − 1) / (n − 1))` in integer arithmetic, so the choice is the
/// same on every machine.
pub fn spread(m: usize, n: usize) -> Vec<usize> {
    if n >= m {
        return (0..m).collect();
    }
    match n {
        0 => Vec::new(),
        1 => vec![0],
        _ => {
            let (num, den) = ((m - 1) as u128, (n - 1) as u128);
            (0..n as u128)
                .map(|k| ((k * num + den / 2) / den) as usize)
                .collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::spread;

    #[test]
    fn keeps_ends_and_is_strictly_increasing() {
        for m in 1..60 {
            for n in 2..70 {
                let v = spread(m, n);
                assert_eq!(v.len(), n.min(m), "m = {m}, n = {n}");
                assert_eq!(v[0], 0);
                assert_eq!(*v.last().unwrap(), m - 1);
                assert!(v.windows(2).all(|w| w[1] > w[0]), "m = {m}, n = {n}: {v:?}");
            }
        }
    }

    /// The gaps between kept indices differ by at most one (even spread).
    #[test]
    fn gaps_are_even() {
        let v = spread(10_001, 2000);
        let gaps: Vec<usize> = v.windows(2).map(|w| w[1] - w[0]).collect();
        let (lo, hi) = (gaps.iter().min().unwrap(), gaps.iter().max().unwrap());
        assert!(hi - lo <= 1, "{lo}..{hi}");
    }
}
