//! Small SVG helpers shared by the pictures: escaping, number formatting, colour maps.

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
