//! Text made inert before it reaches a terminal: every human-readable output (the text of
//! `sweep status`, `show`, `boundaries`, `lines`, progress lines, hints and error messages)
//! passes the text that came from a database or a sweep file (names, descriptions, cost notes,
//! paths, stored error text) through this module, so that a shared database cannot clear the
//! screen, retitle the terminal, ring its bell or reverse the text around it. JSON and CSV
//! outputs are data and stay exact (JSON escapes its control characters itself).
//!
//! Escaped, as `\u{..}` (the code point in hex) or `\n`, `\t`, `\r`: the control characters (C0,
//! DEL, C1: `ESC` starts every terminal escape sequence, `BEL` rings, `NUL` cuts some viewers
//! short), the bidirectional controls (U+061C, U+200E, U+200F, U+202A to U+202E, U+2066 to
//! U+2069: the "Trojan source" overrides), the other invisible format characters of Unicode's
//! category Cf (zero-width spaces and joiners, the word joiner, invisible operators, the byte
//! order mark, interlinear annotations, tag characters, soft hyphen), the line and paragraph
//! separators U+2028 and U+2029, and the non-characters U+FFFE, U+FFFF and U+FFF0 to U+FFF8.
//! Everything else, letters of any script and symbols such as `Γ` or `≥`, passes unchanged. A
//! backslash is not escaped: the exact text is in the JSON output.

use std::borrow::Cow;

/// Whether `c` is escaped (module doc).
pub fn is_unsafe(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{ad}'
                | '\u{600}'..='\u{605}'
                | '\u{61c}'
                | '\u{6dd}'
                | '\u{70f}'
                | '\u{890}'..='\u{891}'
                | '\u{8e2}'
                | '\u{180e}'
                | '\u{200b}'..='\u{200f}'
                | '\u{2028}'..='\u{202e}'
                | '\u{2060}'..='\u{2064}'
                | '\u{2066}'..='\u{206f}'
                | '\u{feff}'
                | '\u{fff0}'..='\u{fffb}'
                | '\u{fffe}'..='\u{ffff}'
                | '\u{110bd}'
                | '\u{110cd}'
                | '\u{13430}'..='\u{1343f}'
                | '\u{1bca0}'..='\u{1bca3}'
                | '\u{1d173}'..='\u{1d17a}'
                | '\u{e0001}'
                | '\u{e0020}'..='\u{e007f}'
        )
}

/// `s` with every unsafe character escaped, newlines and tabs included: for a value printed on
/// one line (a name, a path, a description, a stored error).
pub fn escape(s: &str) -> Cow<'_, str> {
    escaped(s, false)
}

/// `s` with every unsafe character escaped but its line breaks kept: for a whole block of
/// text a command prints (a report, an error message). Tabs are escaped too.
pub fn escape_lines(s: &str) -> Cow<'_, str> {
    escaped(s, true)
}

fn escaped(s: &str, keep_newlines: bool) -> Cow<'_, str> {
    let unsafe_here = |c: char| is_unsafe(c) && !(keep_newlines && c == '\n');
    if !s.chars().any(unsafe_here) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 16);
    for c in s.chars() {
        if !unsafe_here(c) {
            out.push(c);
            continue;
        }
        match c {
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c => out.push_str(&format!("\\u{{{:x}}}", c as u32)),
        }
    }
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terminal_controls_and_bidi_overrides_are_escaped_and_text_is_kept() {
        let forged = "evil\u{1b}]0;pwned\u{7}\u{1b}[2J\u{202e}txet\u{0}end";
        assert_eq!(
            escape(forged),
            "evil\\u{1b}]0;pwned\\u{7}\\u{1b}[2J\\u{202e}txet\\u{0}end"
        );
        assert_eq!(escape("a\nb\tc\rd"), "a\\nb\\tc\\rd");
        assert_eq!(escape_lines("a\nb\tc\u{85}"), "a\nb\\tc\\u{85}");
        for c in [
            '\u{9b}',
            '\u{7f}',
            '\u{200b}',
            '\u{200d}',
            '\u{2066}',
            '\u{2069}',
            '\u{feff}',
            '\u{2028}',
            '\u{e0041}',
            '\u{ad}',
            '\u{61c}',
        ] {
            assert!(is_unsafe(c), "{:x}", c as u32);
            assert!(!escape(&c.to_string()).contains(c));
        }
        // Plain text of any script, and the symbols the reports use, is left alone (borrowed).
        for plain in [
            "Γ ≥ 0.5, E* = 10",
            "Größe — 粒子 ∑",
            "path/to/w.sqlite",
            "a\\nb",
        ] {
            assert!(matches!(escape(plain), Cow::Borrowed(_)), "{plain}");
        }
    }
}
