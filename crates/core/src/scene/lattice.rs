//! Geometry of the initial lattice: how many sites fit along each axis of the box.
//!
//! Sites form a simple square (2D) or cubic (3D) lattice of spacing `a = lattice_spacing * d_max`.
//! Along a periodic axis the `n = floor(L / a)` sites are spread evenly over `L`; along a lateral
//! wall axis likewise, so no particle touches a wall; along the vertical axis the layers are
//! stacked from the floor up with spacing `a`, the first centre at `a / 2`. Without gravity
//! there is no floor to stack on: [`uniform_spacing`] widens the lattice until it just holds the
//! particles and the sites are spread evenly along every axis, so a dilute gas starts homogeneous.

/// Number of lattice sites along each axis for box edges `size` and spacing `a`.
pub fn sites_per_axis(size: &[f64], spacing: f64) -> Vec<usize> {
    size.iter()
        .map(|&l| {
            if spacing > 0.0 {
                (l / spacing).floor().max(0.0) as usize
            } else {
                0
            }
        })
        .collect()
}

/// Total number of lattice sites.
pub fn capacity(size: &[f64], spacing: f64) -> usize {
    sites_per_axis(size, spacing).iter().product()
}

/// The largest spacing `>= min_spacing` whose lattice still holds `count` sites (bisection).
pub(crate) fn uniform_spacing(size: &[f64], min_spacing: f64, count: usize) -> f64 {
    let (mut lo, mut hi) = (
        min_spacing,
        size.iter().cloned().fold(min_spacing, f64::max),
    );
    if capacity(size, hi) >= count {
        return hi;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if capacity(size, mid) >= count {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Coordinates of the first `count` sites, filled lateral axes first, then layer by layer
/// upwards from the floor (`from_floor`), or spread evenly along every axis.
pub(crate) fn site_positions(
    size: &[f64],
    spacing: f64,
    count: usize,
    from_floor: bool,
) -> Vec<Vec<f64>> {
    let n = sites_per_axis(size, spacing);
    let dim = size.len();
    let mut out = Vec::with_capacity(count);
    let mut index = vec![0usize; dim];
    while out.len() < count {
        let pos: Vec<f64> = (0..dim)
            .map(|k| {
                if from_floor && k + 1 == dim {
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
        let sites = site_positions(&[400.0, 9.0], a, 1200, true);
        assert_eq!(sites.len(), 1200);
        // Neighbouring sites are at least `a` apart; all inside the box.
        for s in &sites {
            assert!(s[0] > 0.0 && s[0] < 400.0 && s[1] >= a / 2.0 && s[1] <= 9.0 - a / 2.0);
        }
    }

    #[test]
    fn uniform_lattice_just_holds_the_count() {
        let size = [125.0, 125.0];
        let s = uniform_spacing(&size, 1.01, 2000);
        assert!(capacity(&size, s) >= 2000);
        assert!(capacity(&size, s * 1.001) < 2000);
        let sites = site_positions(&size, s, 2000, false);
        let top = sites.iter().map(|x| x[1]).fold(0.0, f64::max);
        assert!(top > 110.0, "sites reach the top of the box: {top}");
    }
}
