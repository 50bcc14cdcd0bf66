//! Reading a written SVG figure back as a reader's program would: the text of each `<text>`
//! element, its typeset `<tspan>`s joined.

/// Every text of an SVG, each text element's characters joined (tspans included) and trimmed,
/// in document order.
pub fn svg_texts(svg: &str) -> Vec<String> {
    let doc = roxmltree::Document::parse(svg).expect("the SVG parses");
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| {
            n.descendants()
                .filter(|d| d.is_text())
                .filter_map(|d| d.text())
                .collect::<String>()
                .trim()
                .to_string()
        })
        .collect()
}
