//! Writes a figure drawn as SVG in the format its file name asks for: `.svg` as drawn, `.pdf`
//! (vector, the text embedded as text in a subset of the font: svg2pdf) or `.png` (rasterised
//! by resvg at [`PNG_SCALE`] pixels per SVG pixel). Every figure command (`plot`, `lines`,
//! `--profiles`, `--snapshot` pictures) goes through [`write_figure`], which writes through
//! `crate::output` (whole or absent, never over the database).
//!
//! PDF and PNG need a font: the system's (fontdb, loaded once), its sans-serif family set to
//! DejaVu Sans where installed (else Liberation Sans, else Noto Sans, else the first family
//! found). Without any font the conversion fails with a message saying so, rather than
//! writing a figure without its text.

use crate::output::{OutputError, Protected};
use resvg::usvg::{self, fontdb};
use std::path::Path;
use std::sync::{Arc, OnceLock};

/// The file formats a figure can be written in, by the extension of its file name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FigureFormat {
    Svg,
    Pdf,
    Png,
}

/// The extensions a figure's file name may end in, as the error messages name them.
pub(crate) const FIGURE_EXTENSIONS: &str = ".svg, .pdf or .png";

/// Pixels of the PNG per pixel of the SVG: a figure 520 px wide becomes 1560 px, about 460 dpi
/// at a column width of 8.5 cm.
pub(crate) const PNG_SCALE: f32 = 3.0;

impl FigureFormat {
    /// The format of `path` by its extension (case-insensitive); `None` for any other.
    pub(crate) fn of(path: &Path) -> Option<FigureFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "svg" => Some(FigureFormat::Svg),
            "pdf" => Some(FigureFormat::Pdf),
            "png" => Some(FigureFormat::Png),
            _ => None,
        }
    }
}

/// The format of a figure's output `path`, or the refusal naming the allowed extensions (`flag`:
/// the option that named it, `-o` or `--profiles`; empty where none did).
pub(crate) fn figure_format(flag: &str, path: &Path) -> Result<FigureFormat, OutputError> {
    FigureFormat::of(path).ok_or_else(|| {
        let flag = if flag.is_empty() {
            String::new()
        } else {
            format!("{flag} ")
        };
        OutputError::Refused(format!(
            "{flag}{}: a figure's file name must end in {FIGURE_EXTENSIONS}",
            path.display()
        ))
    })
}

/// The system's fonts, loaded once, with the sans-serif family the figures ask for mapped to an
/// installed family (module doc); the error when there is none.
fn fonts() -> Result<Arc<fontdb::Database>, String> {
    static FONTS: OnceLock<Result<Arc<fontdb::Database>, String>> = OnceLock::new();
    FONTS
        .get_or_init(|| {
            let mut db = fontdb::Database::new();
            db.load_system_fonts();
            let families: Vec<String> = db
                .faces()
                .flat_map(|f| f.families.iter().map(|(name, _)| name.clone()))
                .collect();
            let Some(first) = families.first() else {
                return Err(
                    "no font found on this system: PDF and PNG figures need one (install \
                            a font package, e.g. Debian's fonts-dejavu-core), or write .svg"
                        .to_string(),
                );
            };
            let family = ["DejaVu Sans", "Liberation Sans", "Noto Sans"]
                .iter()
                .find(|want| families.iter().any(|f| f == *want))
                .map_or_else(|| first.clone(), |f| f.to_string());
            db.set_sans_serif_family(family);
            Ok(Arc::new(db))
        })
        .clone()
}

/// The figure `svg` converted to `format` (the SVG's own bytes for [`FigureFormat::Svg`]).
pub(crate) fn render(svg: &str, format: FigureFormat) -> Result<Vec<u8>, String> {
    let options = || -> Result<usvg::Options<'static>, String> {
        Ok(usvg::Options {
            fontdb: fonts()?,
            ..usvg::Options::default()
        })
    };
    let tree = || usvg::Tree::from_str(svg, &options()?).map_err(|e| format!("the figure: {e}"));
    match format {
        FigureFormat::Svg => Ok(svg.as_bytes().to_vec()),
        FigureFormat::Pdf => svg2pdf::to_pdf(
            &tree()?,
            svg2pdf::ConversionOptions::default(),
            svg2pdf::PageOptions::default(),
        )
        .map_err(|e| format!("the figure as PDF: {e}")),
        FigureFormat::Png => {
            let tree = tree()?;
            let size = tree
                .size()
                .to_int_size()
                .scale_by(PNG_SCALE)
                .ok_or_else(|| "the figure as PNG: an empty picture".to_string())?;
            let mut pixmap = resvg::tiny_skia::Pixmap::new(size.width(), size.height())
                .ok_or_else(|| "the figure as PNG: an empty picture".to_string())?;
            pixmap.fill(resvg::tiny_skia::Color::WHITE);
            resvg::render(
                &tree,
                resvg::tiny_skia::Transform::from_scale(PNG_SCALE, PNG_SCALE),
                &mut pixmap.as_mut(),
            );
            pixmap
                .encode_png()
                .map_err(|e| format!("the figure as PNG: {e}"))
        }
    }
}

/// Writes the figure `svg` to `path` as SVG, PDF or PNG by the extension of `path` (refused for
/// any other, naming the allowed ones), through `crate::output::write_file` (checked against
/// `protected`; whole or absent).
pub(crate) fn write_figure(
    path: &Path,
    svg: &str,
    protected: &Protected,
) -> Result<(), OutputError> {
    let format = figure_format("", path)?;
    let bytes = render(svg, format)
        .map_err(|e| OutputError::Io(format!("{}: cannot write: {e}", path.display())))?;
    crate::output::write_file(path, bytes, protected)
}

#[cfg(test)]
#[path = "figure_tests.rs"]
mod tests;
