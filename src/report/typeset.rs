//! Typesets the names of physical quantities in a figure's SVG text: a text element whose
//! content begins with [`MARK`] has its plain names (`Gamma`, `E*`, `T_g/E_cb`, `F_max`,
//! `s_crit`, ...) replaced by the symbols a paper prints, variables in italics, subscripts and
//! superscripts as smaller `tspan`s shifted with `dy` (which browsers, usvg and so the PDF and PNG
//! renderings all honour): `Gamma` becomes Γ, `E*` an italic E with a raised star, `T_g/E_cb`
//! an italic T with a subscript g over an italic E with a subscript cb. Text without the mark
//! (a sweep's name in a title, tick labels) is left as drawn.
//!
//! The drawing code writes marked text through plotters (which escapes it); [`typeset_svg`] runs
//! over the finished SVG.

/// The first character of a text element to typeset (a private-use character, removed).
pub(crate) const MARK: char = '\u{E000}';

/// `text` marked for typesetting.
pub(crate) fn marked(text: &str) -> String {
    format!("{MARK}{text}")
}

/// A run of text at one height: its text, its shift (-1 subscript, 0 baseline, 1 superscript)
/// and whether it is italic.
type Run = (String, i32, bool);

/// A run of a name's symbol: text, shift, italic.
type Part = (&'static str, i32, bool);

/// The names typeset, longest first where one begins another: each is a list of runs.
fn names() -> Vec<(&'static str, Vec<Part>)> {
    vec![
        ("Gamma_C", vec![("Γ", 0, false), ("C", -1, false)]),
        ("Gamma", vec![("Γ", 0, false)]),
        ("omega", vec![("ω", 0, true)]),
        ("Delta ", vec![("Δ", 0, false)]),
        (
            "E_d*",
            vec![("E", 0, true), ("d", -1, false), ("*", 1, false)],
        ),
        ("E*", vec![("E", 0, true), ("*", 1, false)]),
        ("T_g", vec![("T", 0, true), ("g", -1, false)]),
        ("E_cb", vec![("E", 0, true), ("cb", -1, false)]),
        ("n_cb", vec![("n", 0, true), ("cb", -1, false)]),
        ("f_lc", vec![("f", 0, true), ("lc", -1, false)]),
        ("D_lat", vec![("D", 0, true), ("lat", -1, false)]),
        ("F_max", vec![("F", 0, true), ("max", -1, false)]),
        ("F_B", vec![("F", 0, true), ("B", -1, false)]),
        ("L_x", vec![("L", 0, true), ("x", -1, false)]),
        ("s_crit", vec![("s", 0, true), ("crit", -1, false)]),
        (
            "A = d",
            vec![("A", 0, true), (" = ", 0, false), ("d", 0, true)],
        ),
        ("A = ", vec![("A", 0, true), (" = ", 0, false)]),
        ("M = ", vec![("M", 0, true), (" = ", 0, false)]),
    ]
}

/// The runs of a (escaped) text: the names replaced, the rest upright on the baseline.
fn runs(text: &str) -> Vec<Run> {
    let table = names();
    let mut out: Vec<Run> = Vec::new();
    let push = |t: &str, shift: i32, italic: bool, out: &mut Vec<Run>| match out.last_mut() {
        Some(last) if last.1 == shift && last.2 == italic => last.0.push_str(t),
        _ => out.push((t.to_string(), shift, italic)),
    };
    let mut rest = text;
    'outer: while let Some(c) = rest.chars().next() {
        // A name counts only at a word's start (`E*` in `E* = 2`, not in `TE*`).
        let at_word_start = out
            .last()
            .and_then(|r| r.0.chars().last())
            .is_none_or(|p| !p.is_ascii_alphanumeric());
        // A power: `^` and its (signed) digits, raised, the minus sign typeset.
        if let Some(after) = rest.strip_prefix('^') {
            let n = after
                .char_indices()
                .take_while(|&(k, c)| c.is_ascii_digit() || (k == 0 && c == '-'))
                .count();
            if n > 0 {
                push(&after[..n].replace('-', "\u{2212}"), 1, false, &mut out);
                rest = &after[n..];
                continue 'outer;
            }
        }
        // The diameter as a unit raised to a power (`d^2`): an italic d, the power next.
        if at_word_start && rest.starts_with("d^") {
            push("d", 0, true, &mut out);
            rest = &rest[1..];
            continue 'outer;
        }
        if at_word_start {
            for (name, parts) in &table {
                if let Some(after) = rest.strip_prefix(name) {
                    // Not a prefix of a longer word (`Gammas`).
                    let word_ends = name.ends_with(|c: char| !c.is_alphanumeric())
                        || after.chars().next().is_none_or(|c| !c.is_alphanumeric());
                    if word_ends {
                        for (t, s, i) in parts {
                            push(t, *s, *i, &mut out);
                        }
                        rest = after;
                        continue 'outer;
                    }
                }
            }
        }
        push(&rest[..c.len_utf8()], 0, false, &mut out);
        rest = &rest[c.len_utf8()..];
    }
    out
}

/// The SVG content of `text` typeset at font size `size` (px).
fn typeset_text(text: &str, size: f64) -> String {
    let shift = |s: i32| match s {
        -1 => 0.25 * size,
        1 => -0.4 * size,
        _ => 0.0,
    };
    let mut out = String::new();
    let mut at = 0.0;
    for (t, s, italic) in runs(text) {
        let dy = shift(s) - at;
        at = shift(s);
        let mut attrs = String::new();
        if dy != 0.0 {
            attrs.push_str(&format!(" dy=\"{}\"", super::svg::n(dy)));
        }
        if s != 0 {
            attrs.push_str(&format!(" font-size=\"{}\"", super::svg::n(0.7 * size)));
        }
        if italic {
            attrs.push_str(" font-style=\"italic\"");
        }
        if attrs.is_empty() {
            out.push_str(&t);
        } else {
            out.push_str(&format!("<tspan{attrs}>{t}</tspan>"));
        }
    }
    out
}

/// `svg` with the content of every marked text element typeset (module doc).
pub(crate) fn typeset_svg(svg: &str) -> String {
    let mut out = String::with_capacity(svg.len() + svg.len() / 8);
    let mut rest = svg;
    while let Some(k) = rest.find(MARK) {
        // The opening tag before the mark, for the font size.
        let before = &rest[..k];
        let tag_start = before.rfind("<text").unwrap_or(0);
        let size = before[tag_start..]
            .split("font-size=\"")
            .nth(1)
            .and_then(|s| s.split('"').next())
            .and_then(|s| s.trim_end_matches("px").parse::<f64>().ok())
            .unwrap_or(12.0);
        out.push_str(before);
        let after = &rest[k + MARK.len_utf8()..];
        let end = after.find('<').unwrap_or(after.len());
        let content = &after[..end];
        let trimmed = content.trim_end();
        out.push_str(&typeset_text(trimmed, size));
        out.push_str(&content[trimmed.len()..]);
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_become_symbols_with_sub_and_superscripts() {
        let svg = format!(
            "<svg><text font-size=\"10\">{}</text><text>Gamma</text></svg>",
            marked("T_g/E_cb against E* (Gamma = 2)")
        );
        let out = typeset_svg(&svg);
        let doc = roxmltree::Document::parse(&out).expect("valid SVG");
        let texts: Vec<roxmltree::Node> = doc
            .descendants()
            .filter(|n| n.has_tag_name("text"))
            .collect();
        let first: String = texts[0]
            .descendants()
            .filter(|n| n.is_text())
            .map(|n| n.text().unwrap_or(""))
            .collect();
        assert_eq!(first, "Tg/Ecb against E* (Γ = 2)");
        // The subscript g: 7 px, shifted 2.5 px down; the star raised.
        let spans: Vec<(String, Option<&str>, Option<&str>)> = texts[0]
            .children()
            .filter(|n| n.has_tag_name("tspan"))
            .map(|n| {
                (
                    n.text().unwrap_or("").to_string(),
                    n.attribute("dy"),
                    n.attribute("font-size"),
                )
            })
            .collect();
        assert_eq!(spans[1], ("g".to_string(), Some("2.5"), Some("7")));
        assert!(spans.contains(&("*".to_string(), Some("-4"), Some("7"))));
        // Unmarked text is untouched, the mark removed.
        assert_eq!(texts[1].text(), Some("Gamma"));
        assert!(!out.contains(MARK));
        // Powers raised, with a true minus sign.
        assert_eq!(
            runs("10^-3 d^2"),
            vec![
                ("10".to_string(), 0, false),
                ("\u{2212}3".to_string(), 1, false),
                (" ".to_string(), 0, false),
                ("d".to_string(), 0, true),
                ("2".to_string(), 1, false)
            ]
        );
        // A name inside a longer word stays.
        assert_eq!(runs("Gammas"), vec![("Gammas".to_string(), 0, false)]);
    }
}
