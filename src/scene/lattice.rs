//! Geometry of the initial lattice: how many sites fit along each axis of the box.
//!
//! Sites form a simple square (2D) or cubic (3D) lattice of spacing `a = lattice_spacing * d_max`.
//! Along a periodic axis the `n = floor(L / a)` sites are spread evenly over `L`; along a lateral
//! wall axis likewise, so no particle touches a wall; along the vertical axis the layers are
//! stacked from the floor up with spacing `a`, the first centre at `a / 2`.

/// Number of lattice sites along each axis for box edges `size` and spacing `a`.
pub fn sites_per_axis(size: &[f64], spacing: f64) -> Vec<usize> {
    size.iter()
        .map(|&l| if spacing > 0.0 { (l / spacing).floor().max(0.0) as usize } else { 0 })
        .collect()
}

/// Total number of lattice sites.
pub fn capacity(size: &[f64], spacing: f64) -> usize {
    sites_per_axis(size, spacing).iter().product()
}

/// Coordinates of the first `count` sites, filled lateral axes first, then layer by layer upwards.
pub fn site_positions(size: &[f64], spacing: f64, count: usize) -> Vec<Vec<f64>> {
    let n = sites_per_axis(size, spacing);
    let dim = size.len();
    let mut out = Vec::with_capacity(count);
    let mut index = vec![0usize; dim];
    while out.len() < count {
        let pos: Vec<f64> = (0..dim)
            .map(|k| {
                if k + 1 == dim {
                    (index[k] as f64 + 0.5) * spacing
                } else {
                    (index[k] as f64 + 0.5) * size[k] / n[k] as f64
                }
            })
            .collect();
        out.push(pos);
        // Odometer increment, lateral axes fastest.
        for k in 0..dim {
            index[k] += 1;
            if index[k] < n[k] {
                break;
            }
            index[k] = 0;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_2d_box_holds_1200() {
        let a = 1.01 * crate::physics::size::diameter_range(1.0, 0.06).1;
        assert!(capacity(&[400.0, 9.0], a) >= 1200);
        let sites = site_positions(&[400.0, 9.0], a, 1200);
        assert_eq!(sites.len(), 1200);
        // Neighbouring sites are at least `a` apart; all inside the box.
        for s in &sites {
            assert!(s[0] > 0.0 && s[0] < 400.0 && s[1] >= a / 2.0 && s[1] <= 9.0 - a / 2.0);
        }
    }
}
