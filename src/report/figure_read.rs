//! Test helpers that read a written figure back as a reader's program would: the text of an
//! SVG (roxmltree), the pixels of a PNG (png), the pages and text of a PDF (lopdf).

pub(crate) use wetgran_testkit::figures::svg_texts;

/// The elements of an SVG with tag `tag`, as parsed.
pub(crate) fn svg_count(svg: &str, tag: &str, attr: Option<(&str, &str)>) -> usize {
    let doc = roxmltree::Document::parse(svg).expect("the SVG parses");
    doc.descendants()
        .filter(|n| n.has_tag_name(tag))
        .filter(|n| attr.is_none_or(|(a, v)| n.attribute(a) == Some(v)))
        .count()
}

/// A decoded PNG: width, height and RGBA pixels.
pub(crate) struct Png {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) rgba: Vec<u8>,
}

impl Png {
    /// The pixel at `(x, y)`.
    pub(crate) fn at(&self, x: u32, y: u32) -> [u8; 4] {
        let k = 4 * (y * self.width + x) as usize;
        [
            self.rgba[k],
            self.rgba[k + 1],
            self.rgba[k + 2],
            self.rgba[k + 3],
        ]
    }

    /// How many pixels have exactly this colour (alpha ignored).
    pub(crate) fn count(&self, rgb: [u8; 3]) -> usize {
        self.rgba.chunks(4).filter(|p| p[..3] == rgb).count()
    }
}

/// Decodes a PNG (8-bit RGBA, as resvg writes it).
pub(crate) fn decode_png(bytes: &[u8]) -> Png {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().expect("a PNG header");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("a PNG frame");
    assert_eq!(info.color_type, png::ColorType::Rgba, "RGBA pixels");
    buf.truncate(info.buffer_size());
    Png {
        width: info.width,
        height: info.height,
        rgba: buf,
    }
}

/// The pages of a PDF: each page's size in points and its text as a PDF reader extracts it
/// (the line breaks it puts between glyphs placed one by one removed).
pub(crate) fn pdf_pages(bytes: &[u8]) -> Vec<((f32, f32), String)> {
    let doc = lopdf::Document::load_mem(bytes).expect("the PDF parses");
    doc.get_pages()
        .iter()
        .map(|(&number, &id)| {
            let page = doc.get_dictionary(id).expect("a page dictionary");
            let media = page
                .get(b"MediaBox")
                .and_then(|m| m.as_array())
                .expect("a media box");
            let v: Vec<f32> = media
                .iter()
                .map(|o| {
                    o.as_float()
                        .or_else(|_| o.as_i64().map(|i| i as f32))
                        .unwrap_or(0.0)
                })
                .collect();
            let text = doc
                .extract_text(&[number])
                .unwrap_or_default()
                .replace('\n', "");
            ((v[2] - v[0], v[3] - v[1]), text)
        })
        .collect()
}
