//! The ticks of a figure's axis, as a paper prints them: on a log axis a labelled tick at every
//! decade and unlabelled minor ticks at 2..9 times it (1, 2 and 5 labelled when fewer than two
//! decades fall inside the range); on a linear axis about five ticks at steps of 1, 2 or 5 times
//! a power of ten. One format per axis: on a linear axis every label has the same number of
//! decimals; on a log axis every label is a plain decimal with the digits it needs (0.1, 1, 10),
//! or every label is a power of ten (`10^-3`, typeset as a superscript) when a decade label would
//! need more than three decimals or five digits.

/// A tick: its value and its label (`None`: a minor tick, unlabelled).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Tick {
    pub(crate) value: f64,
    pub(crate) label: Option<String>,
}

/// The ticks of an axis over `range` (module doc), low to high.
pub(crate) fn axis_ticks(range: (f64, f64), log: bool) -> Vec<Tick> {
    let (lo, hi) = (range.0.min(range.1), range.0.max(range.1));
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return Vec::new();
    }
    if log && lo > 0.0 {
        log_ticks(lo, hi)
    } else {
        linear_ticks(lo, hi)
    }
}

fn log_ticks(lo: f64, hi: f64) -> Vec<Tick> {
    let inside = |v: f64| v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9);
    let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let decades = (a..=b).filter(|&k| inside(10f64.powi(k))).count();
    let majors: &[i32] = if decades >= 2 { &[1] } else { &[1, 2, 5] };
    let mut values: Vec<(f64, bool)> = Vec::new();
    for k in a..=b {
        for m in 1..10 {
            let v = m as f64 * 10f64.powi(k);
            if inside(v) {
                values.push((v, majors.contains(&m)));
            }
        }
    }
    let labelled: Vec<f64> = values.iter().filter(|v| v.1).map(|v| v.0).collect();
    let powers = labelled.iter().any(|&v| !(1e-3..1e5).contains(&v)) && decades >= 2;
    values
        .into_iter()
        .map(|(value, major)| Tick {
            value,
            label: major.then(|| {
                if powers {
                    format!("10^{}", value.log10().round() as i32)
                } else {
                    // Plain decimals, as few digits as the value needs (0.1, 1, 10).
                    let text = format!("{value:.3}");
                    text.trim_end_matches('0').trim_end_matches('.').to_string()
                }
            }),
        })
        .collect()
}

fn linear_ticks(lo: f64, hi: f64) -> Vec<Tick> {
    let raw = (hi - lo) / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw * 0.999)
        .unwrap_or(10.0 * mag);
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    let scientific = step < 1e-3 || hi.abs().max(lo.abs()) >= 1e5;
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last)
        .map(|k| {
            // `+ 0.0` turns -0 into 0.
            let value = k as f64 * step + 0.0;
            Tick {
                value,
                label: Some(if scientific {
                    format!("{value:.1e}")
                } else {
                    format!("{value:.decimals$}")
                }),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(t: &[Tick]) -> Vec<&str> {
        t.iter().filter_map(|t| t.label.as_deref()).collect()
    }

    #[test]
    fn a_log_axis_has_decades_and_minor_ticks() {
        // The quickstart's E* axis, 0.26 .. 5.5: fewer than two decades inside: 1, 2, 5 too.
        let t = axis_ticks((0.26, 5.5), true);
        assert_eq!(labels(&t), vec!["0.5", "1", "2", "5"]);
        assert_eq!(t.len(), 12, "0.3 .. 0.9, 1 .. 5");
        // Three decades: only decades labelled, one format.
        let t = axis_ticks((0.05, 150.0), true);
        assert_eq!(labels(&t), vec!["0.1", "1", "10", "100"]);
        assert!(t.iter().any(|t| t.value == 0.2 && t.label.is_none()));
        // Far from 1: powers of ten on every label.
        let t = axis_ticks((5e-5, 0.2), true);
        assert_eq!(labels(&t), vec!["10^-4", "10^-3", "10^-2", "10^-1"]);
    }

    #[test]
    fn a_linear_axis_has_steps_of_one_two_or_five_with_one_format() {
        let t = axis_ticks((0.0, 21.0), false);
        assert_eq!(labels(&t), vec!["0", "5", "10", "15", "20"]);
        let t = axis_ticks((0.45, 1.32), false);
        assert_eq!(labels(&t), vec!["0.6", "0.8", "1.0", "1.2"]);
        let t = axis_ticks((-0.01, 0.0123), false);
        assert_eq!(
            labels(&t),
            vec!["-0.010", "-0.005", "0.000", "0.005", "0.010"]
        );
    }
}
