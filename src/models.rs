//! The model files every analysis command reads (structure + aerodynamic model, an
//! identification's ensemble members): one place, so that `flutter`, `lco`, `branch` and
//! `tunnel` do not import each other (issue 40 item 2). The reading itself is the
//! library's (`aeroelastic::documents::LoadedPair`, `aeroelastic::ensemble`); this layer
//! only adds the context of the flags and prints the model's warnings.

use std::path::Path;

use aeroelastic::documents::LoadedPair;
use anyhow::Context;

/// Reads a structure file and a model file and builds the section (warnings of an
/// identified model go to stderr).
pub fn load(structure: &Path, model: &Path, chord: Option<f64>) -> anyhow::Result<LoadedPair> {
    // The library's errors name the file and the field.
    let pair = LoadedPair::load(structure, model, chord).context("structure and model files")?;
    for w in pair.warnings() {
        crate::ui::warning!("warning: {}: {w}", model.display());
    }
    Ok(pair)
}

/// Members' laws of an identification.json model (`--ensemble N`) and the ensemble.
pub fn ensemble_laws(
    model: &Path,
    chord: f64,
    n: usize,
) -> anyhow::Result<(
    Vec<Result<aeroelastic::identified::IdentifiedLaw, String>>,
    identify::ensemble::Ensemble,
)> {
    let id = identify::pipeline::Identification::read(model).with_context(|| {
        format!(
            "--ensemble needs an identification.json model ({})",
            model.display()
        )
    })?;
    let opts = aeroelastic::identified::IdentifiedOptions::new(chord);
    let (laws, e) = aeroelastic::ensemble::member_laws(&id, &opts, Some(n))
        .with_context(|| format!("{}: ensemble", model.display()))?;
    Ok((laws, e.clone()))
}
