//! The bifurcation level on the real rig of `tests/data` (reduced copies of the Bristol
//! records, see its README.md): the measured diagram from the nine LCO records and the
//! still-air decay, against the rig's linear model (Theodorsen, the authors' linear
//! structure), nothing fitted to the LCO data beforehand.

use std::path::PathBuf;

use aeroelastic::files::{LoadedModel, StructureFile};
use aeroelastic::section::Section;
use diagnose::bifurcation::{
    diagnose_branches, points_from_records, structure_check, BifurcationOptions, BranchKind,
    Quantity,
};
use diagnose::Effect;
use identify::dataset::read_dataset;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn scenario(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../scenarios")
        .join(name)
}

/// The rig's linear section: the structure file without its published nonlinear terms.
fn linear_section() -> Section {
    let sf = StructureFile::read(&scenario("bristol-spring1.structure.toml")).unwrap();
    let model = LoadedModel::load(&scenario("bristol-spring1.model.toml"), sf.chord).unwrap();
    let st = aeroelastic::structure::Structure::from_modal(&sf.linear).unwrap();
    Section::new(st, model.model, sf.air_density).unwrap()
}

#[test]
fn bristol_bifurcation_diagram_from_the_records() {
    let t = std::time::Instant::now();
    let lco = read_dataset(&data("bristol-spring1")).unwrap();
    let still = read_dataset(&data("bristol-spring1-still-air")).unwrap();
    let (points, uses) = points_from_records(&lco).unwrap();
    assert_eq!(points.len(), 9, "{uses:?}");
    let section = linear_section();
    let structure = structure_check(&[&still], &section);
    let d = diagnose_branches(
        &points,
        &section,
        structure,
        uses,
        &BifurcationOptions::default(),
        vec![],
        "test",
    )
    .unwrap();
    let secs = t.elapsed().as_secs_f64();
    println!("{}", serde_json::to_string_pretty(&d.verdict).unwrap());
    println!("structure: {:?}", d.structure.as_ref().map(|s| &s.summary));
    println!("nominal score {:.3}", d.nominal.errors.score);
    for c in &d.candidates {
        println!(
            "{:40} held-out {:.3} ± {:.3} shrink {:.3} pitch {:.3}° heave {:.2} mm  fit pitch {:.3}°  folds {:?} params {:?} evals {}",
            c.label(),
            c.held_out.score,
            c.score_se,
            c.shrink,
            c.held_out.rms(BranchKind::All, Quantity::Pitch).unwrap_or(f64::NAN).to_degrees(),
            c.held_out.rms(BranchKind::All, Quantity::Heave).unwrap_or(f64::NAN) * 1e3,
            c.fit.errors.rms(BranchKind::All, Quantity::Pitch).unwrap_or(f64::NAN).to_degrees(),
            c.fit.folds.iter().map(|f| f.u).collect::<Vec<_>>(),
            c.parameters.iter().map(|p| (p.spec.name.clone(), p.value)).collect::<Vec<_>>(),
            c.evaluations
        );
    }
    println!("{secs:.1} s");
    let chosen = &d.candidates[d.verdict.candidate.expect("a named verdict")];
    assert!(matches!(
        d.verdict.effect,
        Some(Effect::StructuralPolynomial | Effect::StructuralCubic)
    ));
    let pitch = chosen
        .held_out
        .rms(BranchKind::All, Quantity::Pitch)
        .unwrap();
    assert!(pitch.to_degrees() <= 0.40, "{}", pitch.to_degrees());
}
