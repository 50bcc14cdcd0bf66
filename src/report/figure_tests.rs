use super::*;
use crate::report::figure_read::{decode_png, pdf_pages, svg_texts};

/// A small figure: a white page, a red square, a line of text.
fn figure() -> String {
    "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"200\" height=\"100\">\
     <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\
     <rect x=\"10\" y=\"10\" width=\"40\" height=\"40\" fill=\"rgb(255,0,0)\"/>\
     <text x=\"60\" y=\"40\" font-family=\"sans-serif\" font-size=\"20\">Gamma 1.5</text>\
     </svg>"
        .to_string()
}

#[test]
fn the_extension_chooses_the_format_and_others_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = Protected::none();
    for (name, head) in [
        ("f.svg", &b"<svg"[..]),
        ("f.pdf", &b"%PDF-"[..]),
        ("f.PNG", &b"\x89PNG"[..]),
    ] {
        let path = dir.path().join(name);
        write_figure(&path, &figure(), &p).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert!(bytes.starts_with(head), "{name}");
    }
    let bad = dir.path().join("f.jpg");
    let e = write_figure(&bad, &figure(), &p).unwrap_err();
    assert!(matches!(e, OutputError::Refused(_)));
    assert!(e.to_string().contains(".svg, .pdf or .png"), "{e}");
    assert!(!bad.exists());
    let e = figure_format("-o", Path::new("x.eps")).unwrap_err();
    assert!(e.to_string().starts_with("-o x.eps: "), "{e}");
}

#[test]
fn the_png_is_the_picture_at_three_times_its_size_with_its_text() {
    let png = decode_png(&render(&figure(), FigureFormat::Png).unwrap());
    assert_eq!((png.width, png.height), (600, 300));
    // The red square: 120 x 120 pixels, at (30..150, 30..150).
    assert_eq!(png.at(90, 90), [255, 0, 0, 255]);
    assert_eq!(png.at(20, 90), [255, 255, 255, 255]);
    assert!(png.count([255, 0, 0]) >= 118 * 118);
    // The text: dark pixels right of the square (none there without a font).
    let dark = (180..600)
        .flat_map(|x| (60..130).map(move |y| (x, y)))
        .filter(|&(x, y)| png.at(x, y)[0] < 100)
        .count();
    assert!(dark > 500, "{dark} dark pixels where the text is");
}

#[test]
fn the_pdf_is_one_page_of_the_figure_with_its_text_as_text() {
    let pages = pdf_pages(&render(&figure(), FigureFormat::Pdf).unwrap());
    assert_eq!(pages.len(), 1);
    let ((w, h), text) = &pages[0];
    // One SVG pixel is one point.
    assert_eq!((*w, *h), (200.0, 100.0));
    assert!(text.contains("Gamma 1.5"), "{text:?}");
}

#[test]
fn marked_names_are_typeset_in_every_format() {
    let svg = figure().replace("Gamma 1.5", &crate::report::typeset::marked("Gamma 1.5"));
    let svg = crate::report::typeset::typeset_svg(&svg);
    assert_eq!(svg_texts(&svg), vec!["Γ 1.5"]);
    let pages = pdf_pages(&render(&svg, FigureFormat::Pdf).unwrap());
    assert!(pages[0].1.contains("Γ"), "{:?}", pages[0].1);
}

#[test]
fn a_figure_never_lands_on_the_database() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("w.pdf");
    std::fs::write(&db, b"SQLite format 3\0rest").unwrap();
    let e = write_figure(&db, &figure(), &Protected::database(&db)).unwrap_err();
    assert!(matches!(e, OutputError::Refused(_)), "{e}");
    assert!(
        std::fs::read(&db)
            .unwrap()
            .starts_with(b"SQLite format 3\0")
    );
}
