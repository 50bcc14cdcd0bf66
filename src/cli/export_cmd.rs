//! `wetgran export`: every finished job of a database as tidy CSV or JSON (`report::export`),
//! written as the store reads the rows, with the series in a long-format file of numbers and
//! their text entries in another.

use super::common::DbPick;
use super::common::{Failure, cannot_write, note};
use crate::output::{AtomicFile, Outputs, Protected};
use crate::report::export::{self, Columns, ExportRow, SeriesFile};
use crate::store::Store;
use clap::{Args, ValueEnum};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Output format of `export`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(super) enum ExportFormat {
    Csv,
    Json,
}

#[derive(Debug, Args)]
pub struct ExportArgs {
    #[command(flatten)]
    pub from: DbPick,
    /// Write JSON (everything nested, the series included) instead of CSV.
    #[arg(long, conflicts_with = "format")]
    json: bool,
    /// `csv`; `json` is `--json`.
    #[arg(long, value_enum, default_value = "csv")]
    format: ExportFormat,
    /// Write to this file instead of standard output.
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
    /// Write the series (every array of the observables: time series, profiles, MSD) to
    /// this file in long format, `job_id,series,index,value`, numbers only.
    #[arg(long, value_name = "FILE")]
    series: Option<PathBuf>,
    /// With --series: write the text and true/false entries of the series (the names of the
    /// monitored quantities, the checks' verdicts) to this file, same columns.
    #[arg(long, value_name = "FILE")]
    text: Option<PathBuf>,
    /// Keep every scalar column, also those empty or the same in every row.
    #[arg(long)]
    all: bool,
    /// Write the sidecar (JSON: the system's constants, the columns left out of the rows with
    /// their values, the sweeps, wetgran's version) to this file [default: beside the -o file,
    /// `FILE.meta.json`; none for standard output, a device or a pipe].
    #[arg(long, value_name = "FILE")]
    meta: Option<PathBuf>,
}

/// The suffix of the sidecar written beside an `-o` file (`results.csv.meta.json`).
const META_SUFFIX: &str = ".meta.json";

/// Where the sidecar goes: `--meta FILE`, else beside the file `-o` lands in (symbolic links
/// followed, as the export follows them); none for standard output or an `-o` that is a
/// device or a pipe (`-o /dev/stdout`), where no file is written beside it.
fn meta_path(a: &ExportArgs) -> Option<PathBuf> {
    if let Some(m) = &a.meta {
        return Some(m.clone());
    }
    let out = a.output.as_deref()?;
    let target = crate::output::file_target(out)?;
    let linked = std::fs::symlink_metadata(out).is_ok_and(|m| m.file_type().is_symlink());
    // Named as the user named the output, unless that is a link.
    Some(crate::output::with_suffix(
        if linked { &target } else { out },
        META_SUFFIX,
    ))
}

/// Starts writing the output `path` (whole or not at all: `output::AtomicFile`).
fn create(path: &Path, protected: &Protected) -> Result<AtomicFile, Failure> {
    Ok(AtomicFile::create(path, protected)?)
}

pub(super) fn export(a: ExportArgs) -> Result<(), Failure> {
    let csv = !a.json && a.format == ExportFormat::Csv;
    let (series_path, text_path) = (a.series.as_deref(), a.text.as_deref());
    if text_path.is_some() && series_path.is_none() {
        return Err(Failure::BadInput(
            "--text goes with --series (it holds the text entries of the series)".to_string(),
        ));
    }
    let mut outputs = Outputs::new(Protected::database(&a.from.db));
    let meta_path = meta_path(&a);
    for (flag, path) in [
        ("-o", a.output.as_deref()),
        ("--series", series_path),
        ("--text", text_path),
        ("the sidecar (--meta)", meta_path.as_deref()),
    ] {
        if let Some(p) = path {
            outputs.claim(flag, p)?;
        }
    }
    let protected = outputs.protected();
    let store = Store::open_read_only(&a.from.db)?;
    let sweeps = a.from.select(&store)?;
    let ids: Vec<i64> = sweeps.iter().map(|s| s.id).collect();
    let output = a.output.as_deref();
    let out_name = output.map_or("standard output".to_string(), |p| p.display().to_string());
    // A reader that closes the pipe (`export | head`) ends the export quietly, with the
    // status a shell reports for SIGPIPE, as `main` does for a failed print.
    let out_failed = |e: std::io::Error| {
        if output.is_none() && e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(141);
        }
        Failure::Other(format!("{out_name}: cannot write: {e}"))
    };
    let (mut file, mut stdout) = match output {
        Some(p) => (Some(create(p, protected)?), None),
        None => (None, Some(BufWriter::new(std::io::stdout().lock()))),
    };
    let mut out: &mut dyn Write = match (&mut file, &mut stdout) {
        (Some(f), _) => f,
        (None, Some(s)) => s,
        (None, None) => unreachable!("one of the two"),
    };
    let mut series_files = Vec::new();
    for (path, file) in [
        (series_path, SeriesFile::Numbers),
        (text_path, SeriesFile::Text),
    ] {
        if let Some(p) = path {
            let mut w = create(p, protected)?;
            w.write_all(export::SERIES_HEADER.as_bytes())
                .map_err(cannot_write(p))?;
            series_files.push((w, p, file));
        }
    }
    // Two passes in one read transaction (report::export, "Streaming"): the first finds
    // the columns that carry information, the second writes.
    let mut columns = Columns::new(a.all, csv);
    store.scan_points(&ids, 2, |pass, k, p| {
        let Some(r) = ExportRow::of(&sweeps[k], &p) else {
            return Ok(());
        };
        let (scalars, series) = export::scalars_and_series(&r);
        if pass == 0 {
            columns.add(&r, &scalars);
            return Ok(());
        }
        columns
            .write_row(&mut out, &r, &scalars)
            .map_err(out_failed)?;
        // Each file's write error names that file.
        for (w, p, file) in &mut series_files {
            export::write_series(w, *file, &r, &series).map_err(cannot_write(p))?;
        }
        Ok::<(), Failure>(())
    })?;
    columns.finish(&mut out).map_err(out_failed)?;
    out.flush().map_err(out_failed)?;
    for (w, p, _) in &mut series_files {
        w.flush().map_err(cannot_write(p))?;
    }
    // Every file is put in place only once the whole export is written (and flushed: a write
    // error of any of them leaves all the old files).
    if let Some(f) = file {
        f.commit()?;
    }
    for (w, _, _) in series_files {
        w.commit()?;
    }
    let names: Vec<String> = sweeps.iter().map(|s| s.name.clone()).collect();
    match &meta_path {
        Some(p) => {
            let meta = columns.meta(&a.from.db.display().to_string(), &names);
            let text = serde_json::to_string_pretty(&meta).expect("serializes") + "\n";
            super::common::write_file(p, text, protected)?;
            note(&format!(
                "export: the system's constants and the columns left out are in {}",
                p.display()
            ));
        }
        None => note(
            "export: no sidecar beside standard output or a stream: the system's constants \
             left out of the rows are not written (--meta FILE writes them, --all keeps every \
             column)",
        ),
    }
    let left_out = columns.left_out();
    if left_out > 0 {
        note(&format!(
            "export: {left_out} scalar column(s) left out, empty or the same in every row \
             (--all keeps them)"
        ));
    }
    if series_path.is_none() {
        eprintln!(
            "export: scalar columns only; the series (time series, profiles) go to \
             --series FILE"
        );
    }
    Ok(())
}
