//! What a point's own numbers say beside its label (docs/observables.md "Classification",
//! rule 5 and "Borderline"): the evidence that bounds the line rule, and the decisions that lie
//! close to a threshold.
//!
//! **Own evidence** ([`overrule_line`]). A line of constant Gamma places a homogeneous mobile
//! point on the fluid or the gas side of its jump or inflection. That placement may not
//! contradict what the point itself shows. With the thin-thread well a colliding pair stays
//! bonded only if its normal relative kinetic energy at the well's edge is below `E_cb`; in a
//! state at temperature `T_g` the collision-flux-weighted normal energy `1/2 mu v_n^2` is
//! exponential with mean `T_g` (any dimension), so a fraction `1 - exp(-E_cb / T_g)` of the
//! collisions can bind. A wet point with `T_g / E_cb >= gas_evidence_temperature` (default 10:
//! at most 9.5 % bind) and at most `gas_evidence_bridges` bridges per grain (default 0.2, a
//! tenth of a bonded bed's 2) is a gas; one with `T_g / E_cb <= fluid_evidence_temperature`
//! (default 1: 63 % bind) and at least `fluid_evidence_bridges` (default 1, half a bed's) is a
//! fluid. Where the line says otherwise the point's evidence decides, and the conflict is
//! flagged borderline. Dry points and coexistences are not affected.
//!
//! **Borderline** ([`borderline`]): a decision whose input lies within a factor
//! [`BORDERLINE_FACTOR`] of its threshold (or within [`BORDERLINE_CONTRAST`] of a fraction's),
//! a fluid-gas decision by the per-point `gas_temperature` fallback near that threshold, a
//! solid-mobile decision that fell back to the temperature because the mobility was not
//! measured, and a line placement overruled by the point's own evidence.

use super::{DecisionInputs, FluidGasFrom, Mobility, Phase};
use crate::observe::{Observables, Thresholds};

/// The phase a wet homogeneous point's own temperature and bridges demand, if any (module doc).
pub(crate) fn own_evidence(obs: &Observables, th: &Thresholds) -> Option<Phase> {
    if obs.temperature_unit_name != "E_cb" {
        return None;
    }
    let (t, b) = (obs.granular_temperature_reduced, obs.bridges_per_particle);
    if t >= th.gas_evidence_temperature && b <= th.gas_evidence_bridges {
        Some(Phase::G)
    } else if t <= th.fluid_evidence_temperature && b >= th.fluid_evidence_bridges {
        Some(Phase::F)
    } else {
        None
    }
}

/// Rule 5: where a line placed a homogeneous mobile point against its own evidence, the
/// evidence decides: returns the new phase and records the conflict in `d`.
pub(crate) fn overrule_line(obs: &Observables, d: &mut DecisionInputs) -> Option<Phase> {
    let FluidGasFrom::Line {
        gamma,
        method,
        e_star_boundary,
    } = &d.fluid_gas
    else {
        return None;
    };
    let line_said = d.whole.phase;
    if d.split || !matches!(line_said, Phase::F | Phase::G) {
        return None;
    }
    let own = own_evidence(obs, &d.thresholds).filter(|&p| p != line_said)?;
    let th = &d.thresholds;
    d.reason = format!(
        "{}; overruled by the point's own evidence (rule 5): T_g/E_cb = {:.3} and {:.3} \
         bridges per grain are a {}'s ({})",
        d.reason,
        obs.granular_temperature_reduced,
        obs.bridges_per_particle,
        if own == Phase::G { "gas" } else { "fluid" },
        if own == Phase::G {
            format!(
                ">= {} and <= {}",
                th.gas_evidence_temperature, th.gas_evidence_bridges
            )
        } else {
            format!(
                "<= {} and >= {}",
                th.fluid_evidence_temperature, th.fluid_evidence_bridges
            )
        }
    );
    d.fluid_gas = FluidGasFrom::OwnEvidence {
        gamma: *gamma,
        method: method.clone(),
        e_star_boundary: *e_star_boundary,
        line_said,
    };
    d.whole.phase = own;
    Some(own)
}

/// A decision is borderline when its input lies within this factor of its threshold (either
/// side): `D_lat` against `solid_diffusion`, `Delta` against the noise threshold.
pub(crate) const BORDERLINE_FACTOR: f64 = 2.0;
/// The contrast of a coexistence, the fraction of its dense bins' grains that are cluster
/// members, and the fraction of a dense region's members still in their cage, are borderline
/// within this distance of their thresholds.
pub(crate) const BORDERLINE_CONTRAST: f64 = 0.1;

/// Whether `x` lies within [`BORDERLINE_FACTOR`] of a positive threshold `t`.
fn near(x: f64, t: f64) -> bool {
    t > 0.0 && x > 0.0 && x / t < BORDERLINE_FACTOR && t / x < BORDERLINE_FACTOR
}

/// The borderline decisions of a classification (see [`DecisionInputs::borderline`]).
pub(crate) fn borderline(d: &DecisionInputs) -> Vec<String> {
    let th = &d.thresholds;
    let mut out = Vec::new();
    let regions = [
        ("whole", Some(&d.whole)),
        ("dense", d.dense.as_ref()),
        ("dilute", d.dilute.as_ref()),
    ];
    for (name, r) in regions {
        let Some(r) = r else { continue };
        if (name == "whole") == d.split {
            continue;
        }
        if let (Mobility::Displacement, Some(x)) = (r.mobility_from, r.diffusion)
            && near(x, th.solid_diffusion)
        {
            out.push(format!(
                "{name}: D_lat = {x:.3e} near solid_diffusion = {}",
                th.solid_diffusion
            ));
        }
        if let (Mobility::Displacement, Some(f)) = (r.mobility_from, r.members_still)
            && (f - th.still_members).abs() < BORDERLINE_CONTRAST
        {
            out.push(format!(
                "{name}: members still in their cage {f:.2} near still_members = {}",
                th.still_members
            ));
        }
        if th.mobility != Mobility::Temperature && r.mobility_from == Mobility::Temperature {
            out.push(format!(
                "{name}: mobility not measured (the window is shorter than the mobility lag): \
                 solid versus mobile by T_g = {:.3} against solid_temperature = {}",
                r.temperature, th.solid_temperature
            ));
        }
        // The per-point fallback decides fluid versus gas for a coexistence's regions and for
        // a homogeneous point no line placed.
        let fallback = d.split
            || matches!(
                d.fluid_gas,
                FluidGasFrom::PointFallback | FluidGasFrom::LineWithoutTransition { .. }
            );
        if fallback
            && matches!(r.phase, Phase::F | Phase::G)
            && near(r.temperature, th.gas_temperature)
        {
            out.push(format!(
                "{name}: T_g = {:.3} near gas_temperature = {} (the per-point fallback decided \
                 fluid versus gas)",
                r.temperature, th.gas_temperature
            ));
        }
    }
    if let FluidGasFrom::OwnEvidence { line_said, .. } = d.fluid_gas {
        out.push(format!(
            "the line placed the point {line_said}, its own temperature and bridges say {} \
             (rule 5)",
            d.whole.phase
        ));
    }
    if let Some(t) = &d.coexistence {
        if let Some(q) = t.noise_threshold
            && near(t.delta, q)
            && t.contrast >= th.coexistence_contrast
        {
            out.push(format!(
                "Delta {} = {:.4} near the noise threshold {q:.4}",
                t.profile, t.delta
            ));
        }
        if t.noise_threshold.is_some_and(|q| t.delta > q)
            && (t.contrast - th.coexistence_contrast).abs() < BORDERLINE_CONTRAST
        {
            out.push(format!(
                "contrast {:.2} near coexistence_contrast = {}",
                t.contrast, th.coexistence_contrast
            ));
        }
        // The bonded part decides between a coexistence and a modulated homogeneous state
        // only where the profile's spread and contrast pass.
        if let Some(f) = t.member_fraction
            && t.noise_threshold.is_some_and(|q| t.delta > q)
            && t.contrast >= th.coexistence_contrast
            && (f - th.cluster_fraction).abs() < BORDERLINE_CONTRAST
        {
            out.push(format!(
                "cluster members {f:.2} of the dense bins near cluster_fraction = {}",
                th.cluster_fraction
            ));
        }
    }
    out
}
