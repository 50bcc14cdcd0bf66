//! `[sweep.continuation]` of a sweep file: the table as written, the continuation it asks for,
//! and its checks (the axis exists and is numeric, the direction and the first start are known
//! words).

use super::{AXIS_ALIASES, Axis, SweepError, line_of};
use serde::Deserialize;
use toml::Spanned;

/// `[sweep.continuation]` as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawContinuation {
    /// The axis to continue along (its name in the file, e.g. `e_star`, or its scene key).
    pub axis: Spanned<String>,
    /// `"ascending"` (default) or `"descending"` axis values.
    pub direction: Option<Spanned<String>>,
    /// How the first point of each chain starts: `"hot"` (default) or `"cold"`.
    pub first: Option<Spanned<String>>,
}

/// A continuation along one axis (docs/model.md 7 hysteresis; issue "runs to stationarity"): the
/// jobs whose `initial.start` is `"continue"` form one chain per combination of the other axes
/// and replica; each starts from the final state of its predecessor along `axis`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Continuation {
    /// Index of the axis in [`SweepFile::axes`].
    pub axis: usize,
    /// Chains run from the largest value down.
    pub descending: bool,
    /// The start of each chain's first point (hot or cold).
    pub first: wetgran_core::scene::StartMode,
    /// Line of `[sweep.continuation]` in the sweep file.
    pub line: usize,
}

/// Checks `[sweep.continuation]`: the axis exists and is numeric, direction and first start are
/// known words. Unless the scene or an axis sets `initial.start`, every job continues.
pub(super) fn parse_continuation(
    text: &str,
    file: &str,
    c: &Spanned<RawContinuation>,
    axes: &[Axis],
    scene_tree: &mut toml::Table,
) -> Result<Continuation, SweepError> {
    let line = line_of(text, c.span().start);
    let raw = c.get_ref();
    let at = |s: &Spanned<String>| Some(line_of(text, s.span().start));
    let name = raw.axis.get_ref().trim();
    let key = AXIS_ALIASES
        .iter()
        .find(|(n, _, _)| *n == name)
        .map_or(name, |(_, k, _)| *k);
    let axis_err =
        |msg: String| SweepError::new(file, at(&raw.axis), "sweep.continuation.axis", msg);
    let Some(axis) = axes.iter().position(|a| a.name == name || a.key == key) else {
        let names: Vec<&str> = axes.iter().map(|a| a.name.as_str()).collect();
        let names = if names.is_empty() {
            "none".to_string()
        } else {
            names.join(", ")
        };
        return Err(axis_err(format!(
            "= {name:?} is not an axis of this sweep (axes: {names})"
        )));
    };
    if axes[axis].values.iter().any(|v| v.as_f64().is_none()) {
        return Err(axis_err(format!(
            "= {name:?}: a continuation runs along a numeric axis; {} has non-numeric values",
            axes[axis].key
        )));
    }
    if axes[axis].key == "initial.start" || axes[axis].key == "initial.seed" {
        return Err(axis_err(format!(
            "= {name:?}: cannot continue along {}",
            axes[axis].key
        )));
    }
    let descending = match raw.direction.as_ref().map(|d| (d, d.get_ref().as_str())) {
        None | Some((_, "ascending")) => false,
        Some((_, "descending")) => true,
        Some((d, other)) => {
            return Err(SweepError::new(
                file,
                at(d),
                "sweep.continuation.direction",
                format!("= {other:?} is not allowed: must be \"ascending\" or \"descending\""),
            ));
        }
    };
    let first = match raw.first.as_ref().map(|d| (d, d.get_ref().as_str())) {
        None | Some((_, "hot")) => wetgran_core::scene::StartMode::Hot,
        Some((_, "cold")) => wetgran_core::scene::StartMode::Cold,
        Some((d, other)) => {
            return Err(SweepError::new(
                file,
                at(d),
                "sweep.continuation.first",
                format!("= {other:?} is not allowed: must be \"hot\" or \"cold\""),
            ));
        }
    };
    let start_set = scene_tree
        .get("initial")
        .and_then(|i| i.get("start"))
        .is_some()
        || axes.iter().any(|a| a.key == "initial.start");
    if !start_set {
        let initial = scene_tree
            .entry("initial")
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        if let toml::Value::Table(t) = initial {
            t.insert("start".into(), toml::Value::String("continue".into()));
        }
    }
    Ok(Continuation {
        axis,
        descending,
        first,
        line,
    })
}
