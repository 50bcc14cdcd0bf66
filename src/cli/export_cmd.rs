//! `wetgran export`: every finished job of a database as tidy CSV or JSON (`report::export`),
//! written as the store reads the rows, with the series in a long-format file of numbers and
//! their text entries in another.

use super::common::{Failure, exit, select};
use super::sweep_cmd::ExportFormat;
use crate::report::export::{self, Columns, ExportRow, JsonWriter};
use crate::store::Store;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::process::ExitCode;

/// What `export` writes where.
pub(super) struct ExportTo<'a> {
    pub format: ExportFormat,
    pub output: Option<&'a Path>,
    pub series: Option<&'a Path>,
    pub text: Option<&'a Path>,
    /// Every scalar column, the empty and constant ones included.
    pub all: bool,
}

fn create(path: &Path) -> Result<BufWriter<std::fs::File>, Failure> {
    std::fs::File::create(path)
        .map(BufWriter::new)
        .map_err(|e| Failure::Other(format!("{}: cannot write: {e}", path.display())))
}

/// `wetgran export`.
pub(super) fn export(db: &Path, name: Option<&str>, to: ExportTo) -> ExitCode {
    exit((|| {
        if to.text.is_some() && to.series.is_none() {
            return Err(Failure::BadInput(
                "--text goes with --series (it holds the text entries of the series)".to_string(),
            ));
        }
        let store = Store::open_read_only(db)?;
        let sweeps = select(&store, name)?;
        let ids: Vec<i64> = sweeps.iter().map(|s| s.id).collect();
        let out_name = to
            .output
            .map_or("standard output".to_string(), |p| p.display().to_string());
        // A reader that closes the pipe (`export | head`) ends the export quietly, with the
        // status a shell reports for SIGPIPE, as `main` does for a failed print.
        let out_failed = |e: std::io::Error| {
            if to.output.is_none() && e.kind() == std::io::ErrorKind::BrokenPipe {
                std::process::exit(141);
            }
            Failure::Other(format!("{out_name}: cannot write: {e}"))
        };
        let mut out: Box<dyn Write> = match to.output {
            Some(p) => Box::new(create(p)?),
            None => Box::new(BufWriter::new(std::io::stdout().lock())),
        };
        let mut series_out = to.series.map(create).transpose()?;
        let mut text_out = to.text.map(create).transpose()?;
        let file_failed = |p: Option<&Path>| {
            let name = p.map(|p| p.display().to_string()).unwrap_or_default();
            move |e: std::io::Error| Failure::Other(format!("{name}: cannot write: {e}"))
        };
        for (w, p) in [(&mut series_out, to.series), (&mut text_out, to.text)] {
            if let Some(w) = w {
                w.write_all(export::SERIES_HEADER.as_bytes())
                    .map_err(file_failed(p))?;
            }
        }
        // Two passes in one read transaction (report::export, "Streaming"): the first finds
        // the columns that carry information, the second writes.
        let mut columns = Columns::new(to.all);
        let mut json = JsonWriter::default();
        let mut started = false;
        store.scan_points(&ids, 2, |pass, k, p| {
            let Some(r) = ExportRow::of(&sweeps[k], &p) else {
                return Ok(());
            };
            let (scalars, series) = export::scalars_and_series(&r);
            if pass == 0 {
                columns.add(&r, &scalars);
                return Ok(());
            }
            if !started {
                columns.finish_first_pass();
                if let ExportFormat::Csv = to.format {
                    columns.write_csv_header(&mut out).map_err(out_failed)?;
                }
                started = true;
            }
            match to.format {
                ExportFormat::Csv => columns
                    .write_csv_row(&mut out, &r, &scalars)
                    .map_err(out_failed)?,
                ExportFormat::Json => json
                    .row(&mut out, &columns.json_row(&r, &scalars))
                    .map_err(out_failed)?,
            }
            if let Some(w) = series_out.as_mut() {
                let text = text_out.as_mut().map(|t| t as &mut dyn Write);
                export::write_series(w, text, &r, &series).map_err(file_failed(to.series))?;
            }
            Ok::<(), Failure>(())
        })?;
        if !started {
            // No finished job: the header alone, or an empty array.
            columns.finish_first_pass();
            if let ExportFormat::Csv = to.format {
                columns.write_csv_header(&mut out).map_err(out_failed)?;
            }
        }
        if let ExportFormat::Json = to.format {
            json.finish(&mut out).map_err(out_failed)?;
        }
        out.flush().map_err(out_failed)?;
        for (w, p) in [(&mut series_out, to.series), (&mut text_out, to.text)] {
            if let Some(w) = w {
                w.flush().map_err(file_failed(p))?;
            }
        }
        let left_out = columns.left_out();
        if left_out > 0 {
            eprintln!(
                "export: {left_out} scalar column(s) left out, empty or the same in every row \
                 (--all keeps them)"
            );
        }
        if to.series.is_none() {
            eprintln!(
                "export: scalar columns only; the series (time series, profiles) go to \
                 --series FILE"
            );
        }
        Ok(())
    })())
}
