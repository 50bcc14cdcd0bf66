//! Small SVG helpers shared by the pictures: escaping, number formatting, a colour map.

/// Escapes text for SVG (and HTML): the markup characters, and the characters `terminal` makes
/// inert (control characters are not allowed in XML; bidirectional overrides would reorder the
/// text around them); line breaks are kept.
pub(super) fn esc(s: &str) -> String {
    crate::terminal::escape_lines(s)
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The opening tag of an SVG picture of `w` x `h` pixels (sans-serif text, 11 px).
pub(super) fn open(w: f64, h: f64) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" \
         font-family=\"sans-serif\" font-size=\"11\">\n",
        n(w),
        n(h)
    )
}

/// A number with few digits for coordinates (keeps files small).
pub(super) fn n(v: f64) -> String {
    let r = (v * 100.0).round() / 100.0;
    if r == r.trunc() {
        format!("{}", r as i64)
    } else {
        format!("{r}")
    }
}

/// A tick label: plain for ordinary magnitudes, scientific for very small or large ones.
pub(super) fn label(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() >= 1e4 || v.abs() < 1e-2 {
        format!("{v:.2e}")
    } else {
        format!("{v:.3}")
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    }
}

/// A perceptually ordered colour map (dark blue - teal - yellow) for `u` in `[0, 1]`.
pub(super) fn colour(u: f64) -> String {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (0.0, [68.0, 1.0, 84.0]),
        (0.25, [59.0, 82.0, 139.0]),
        (0.5, [33.0, 145.0, 140.0]),
        (0.75, [94.0, 201.0, 98.0]),
        (1.0, [253.0, 231.0, 37.0]),
    ];
    let u = if u.is_finite() {
        u.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let k = STOPS
        .windows(2)
        .position(|w| u <= w[1].0)
        .unwrap_or(STOPS.len() - 2);
    let (u0, c0) = STOPS[k];
    let (u1, c1) = STOPS[k + 1];
    let f = (u - u0) / (u1 - u0);
    let c: Vec<u8> = (0..3)
        .map(|i| (c0[i] + f * (c1[i] - c0[i])).round() as u8)
        .collect();
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// Eight distinct colours for small integers (bridge counts 0..=7+).
pub(super) fn category(k: usize) -> &'static str {
    const C: [&str; 8] = [
        "#bdbdbd", "#4575b4", "#74add1", "#abd9e9", "#fee090", "#fdae61", "#f46d43", "#d73027",
    ];
    C[k.min(C.len() - 1)]
}

/// The ticks of an axis over `range`: every grid value when there are at most `max` distinct
/// ones inside it (a sweep's axis values), else every decade on a log axis (1, 2, 5 times each
/// decade when the range spans less than two), else `max` evenly spaced values.
pub(super) fn grid_ticks(values: &[f64], range: (f64, f64), log: bool, max: usize) -> Vec<f64> {
    let (lo, hi) = (range.0.min(range.1), range.0.max(range.1));
    let mut grid: Vec<f64> = values
        .iter()
        .copied()
        .filter(|v| v.is_finite() && *v >= lo && *v <= hi)
        .collect();
    grid.sort_by(f64::total_cmp);
    grid.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * a.abs().max(b.abs()));
    if !grid.is_empty() && grid.len() <= max {
        return grid;
    }
    if log && lo > 0.0 {
        let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        let steps: &[f64] = if (hi / lo).log10() < 2.0 {
            &[1.0, 2.0, 5.0]
        } else {
            &[1.0]
        };
        return (a..=b)
            .flat_map(|k| steps.iter().map(move |s| s * 10f64.powi(k)))
            .filter(|v| *v >= lo && *v <= hi)
            .collect();
    }
    let n = max.max(2);
    (0..n)
        .map(|k| lo + (hi - lo) * k as f64 / (n - 1) as f64)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_the_grid_values_or_decades() {
        let grid = [0.3, 0.6, 1.2, 2.4, 4.755];
        assert_eq!(grid_ticks(&grid, (0.25, 5.0), true, 12), grid.to_vec());
        // Too many grid values: decades (with 2 and 5 inside a range under two decades).
        let dense: Vec<f64> = (0..40).map(|k| 0.1 * 1.1f64.powi(k)).collect();
        assert_eq!(
            grid_ticks(&dense, (0.09, 5.0), true, 12),
            vec![0.1, 0.2, 0.5, 1.0, 2.0, 5.0]
        );
        assert_eq!(
            grid_ticks(&dense, (0.09, 500.0), true, 12),
            vec![0.1, 1.0, 10.0, 100.0]
        );
        // Linear with too many values: evenly spaced.
        assert_eq!(
            grid_ticks(&dense, (0.0, 1.0), false, 3),
            vec![0.0, 0.5, 1.0]
        );
    }
}
