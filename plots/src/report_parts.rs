//! What the diagnosis and bifurcation reports share (their file names, the still-air
//! structure table): below both, so neither report imports the other (issue 40,
//! docs/DECISIONS.md "No import circles, checked").

use crate::report::Report;

/// File name of the report written by [`write_diagnosis_outputs`](crate::write_diagnosis_outputs).
pub const DIAGNOSIS_HTML: &str = "diagnosis.html";
/// Sub-folder of the output folder that holds the figure files.
pub const FIGURES_DIR: &str = "figures";

/// The still-air decays' table ([`diagnose::structure::StructureCheck`]), or `none` in
/// words when no decay was analysed.
pub(crate) fn structure_section(
    r: &mut Report,
    s: Option<&diagnose::structure::StructureCheck>,
    none: &str,
) {
    match s {
        Some(s) => {
            let rows: Vec<Vec<String>> = s
                .modes
                .iter()
                .map(|m| {
                    vec![
                        m.case.clone(),
                        m.dof.clone(),
                        format!("{:.4}", m.measured_hz),
                        format!("{:.4}", m.given_hz),
                        format!("{:+.2} %", 100.0 * m.frequency_error),
                        format!("{:.4}", m.measured_zeta),
                        format!("{:.4}", m.given_zeta),
                        format!("{:+.2} %", 100.0 * m.backbone_change),
                        format!("{:.1}", m.exp_over_linear),
                        m.signature.clone(),
                    ]
                })
                .collect();
            table(
                r,
                "Still-air modes measured (smallest analysed amplitudes) against the given \
                 structure's; backbone = frequency change from small to large amplitude; \
                 exp/lin > 1: a linear (dry-friction) envelope",
                &[
                    "record",
                    "DOF",
                    "f measured [Hz]",
                    "f given [Hz]",
                    "Δf",
                    "ζ measured",
                    "ζ given",
                    "backbone",
                    "exp/lin",
                    "signature",
                ],
                &rows,
            );
        }
        None => {
            r.text(none);
        }
    }
}

pub(crate) fn table(r: &mut Report, caption: &str, header: &[&str], rows: &[Vec<String>]) {
    let header: Vec<String> = header.iter().map(|h| h.to_string()).collect();
    r.table(caption, &header, rows);
}
