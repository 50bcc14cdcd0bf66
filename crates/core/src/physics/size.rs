//! Size distributions (docs/model.md section 5, Eqs. 2.21-2.22).

use rand::Rng;

/// Largest polydispersity a uniform distribution of positive diameters allows, `1/sqrt(3)`.
pub(crate) const MAX_POLYDISPERSITY: f64 = 0.577_350_269_189_625_8;

/// Smallest and largest diameter for mean `d` and polydispersity `sigma_p`:
/// `d_min/max = d (1 -+ sqrt(3) sigma_p)` (Eq. 2.22).
pub(crate) fn diameter_range(d_mean: f64, sigma_p: f64) -> (f64, f64) {
    let half_width = 3f64.sqrt() * sigma_p;
    (d_mean * (1.0 - half_width), d_mean * (1.0 + half_width))
}

/// Draws `n` diameters uniform on `[d_min, d_max]` (Eq. 2.21).
pub(crate) fn draw_diameters<R: Rng>(rng: &mut R, n: usize, d_mean: f64, sigma_p: f64) -> Vec<f64> {
    let (lo, hi) = diameter_range(d_mean, sigma_p);
    (0..n)
        .map(|_| {
            if hi > lo {
                rng.gen_range(lo..=hi)
            } else {
                d_mean
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn sample_polydispersity_matches_definition() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
        let d = draw_diameters(&mut rng, 200_000, 1.0, 0.06);
        let n = d.len() as f64;
        let mean = d.iter().sum::<f64>() / n;
        let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        assert!((mean - 1.0).abs() < 1e-3, "mean {mean}");
        // sigma_p = std / mean for a uniform distribution (Eq. 2.22).
        assert!(
            (var.sqrt() / mean - 0.06).abs() < 5e-4,
            "sigma {}",
            var.sqrt()
        );
        let (lo, hi) = diameter_range(1.0, 0.06);
        assert!(d.iter().all(|&x| x >= lo && x <= hi));
    }
}
