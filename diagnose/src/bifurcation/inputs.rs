//! The choices a user's inputs imply for the bifurcation level, as library functions that
//! the binary (`aeroform diagnose --measured-branch`) and the Python package both call
//! (issue 40 item 2): which reader a measured diagram needs ([`read_measured`]: a CSV
//! table, or a data-set folder of records whose amplitudes are read by
//! [`points_from_records`]) and where the given structure comes from
//! ([`given_structure`]: a structure file, else the first data set whose manifest has a
//! `[structure]`).

use std::path::Path;

use aeroelastic::branch::{read_measured_diagram, MeasuredDiagram};
use aeroelastic::files::StructureFile;
use aeroelastic::structure::Structure;
use identify::dataset::{read_dataset, Dataset};

use super::points::{points_from_records, RecordUse};
use crate::{Error, Result};

/// A measured bifurcation diagram as given: its points (and any `onset`/`none` rows of a
/// table), the records it was read from when the input is a data-set folder, and how each
/// record was used.
#[derive(Debug, Clone)]
pub struct MeasuredInput {
    /// Measured amplitudes (peak, first harmonic: pitch \[rad\], heave \[m\]; U [m/s]),
    /// onsets and absences.
    pub diagram: MeasuredDiagram,
    /// The data set when the input is a folder of records (its still-air runs are decays
    /// for the structure check); `None` for a table.
    pub records: Option<Dataset>,
    /// Per record of `records`: the role it was given (branch point, decay, skipped) and
    /// why.
    pub uses: Vec<RecordUse>,
}

/// Reads a measured bifurcation diagram: a folder is a data set of records (each free
/// run's limit-cycle amplitudes become a point, still-air runs decays; DATA_FORMAT.md
/// "Measured bifurcation diagram from records"); a file is the CSV table
/// (`aeroelastic::branch::read_measured_diagram`, rows `point`, `onset`, `none`).
///
/// # Errors
/// [`Error::Identify`] naming the folder when its data set is refused;
/// [`Error::Aeroelastic`] naming the table when it is refused (line and column in the
/// message); the errors of [`points_from_records`].
pub fn read_measured(path: &Path) -> Result<MeasuredInput> {
    if path.is_dir() {
        let set = read_dataset(path)
            .map_err(|e| Error::identify(format!("reading {}", path.display()), e))?;
        let (points, uses) = points_from_records(&set)?;
        Ok(MeasuredInput {
            diagram: MeasuredDiagram {
                points,
                ..MeasuredDiagram::default()
            },
            records: Some(set),
            uses,
        })
    } else {
        let diagram = read_measured_diagram(path)
            .map_err(|e| Error::aeroelastic("measured bifurcation diagram", e))?;
        Ok(MeasuredInput {
            diagram,
            records: None,
            uses: Vec::new(),
        })
    }
}

/// The given (nominal) structure of a bifurcation-level diagnosis and where it came from.
#[derive(Debug, Clone)]
pub struct GivenStructure {
    /// The structure (masses, springs, dampers, nonlinear terms per unit span).
    pub structure: Structure,
    /// Air density ρ \[kg/m³\] of the structure file or the data set's section.
    pub air_density: f64,
    /// Chord B \[m\] when the source gives one (a structure file may not).
    pub chord: Option<f64>,
    /// Where it came from, for the report (`path` of the file, or `[structure] of DIR`).
    pub source: String,
}

/// The given structure: the structure file `file` when there is one, else the
/// `[structure]` of the first of `sets` whose manifest has one (the measured records
/// first, then the free runs, as the caller orders them).
///
/// # Errors
/// [`Error::Aeroelastic`] naming the file when it is refused; [`Error::Data`] when no file
/// is given and no data set has a `[structure]`, or when a manifest's structure is not a
/// valid one (naming the manifest).
pub fn given_structure(file: Option<&Path>, sets: &[&Dataset]) -> Result<GivenStructure> {
    if let Some(path) = file {
        let at = |e| Error::aeroelastic(format!("reading {}", path.display()), e);
        let sf = StructureFile::read(path).map_err(at)?;
        return Ok(GivenStructure {
            structure: sf.structure().map_err(at)?,
            air_density: sf.air_density,
            chord: sf.chord,
            source: path.display().to_string(),
        });
    }
    let Some((set, modal)) = sets
        .iter()
        .find_map(|d| d.manifest.structure.as_ref().map(|m| (d, m)))
    else {
        let names: Vec<String> = sets.iter().map(|d| d.root.display().to_string()).collect();
        return Err(Error::data(
            if names.is_empty() {
                "(none)".to_string()
            } else {
                names.join(", ")
            },
            "no structure: give a structure file (`--structure S`; Python `structure=`), or \
             data sets whose manifest has a [structure]",
        ));
    };
    let manifest = set.root.join("manifest.toml");
    let structure = Structure::from_modal(modal)
        .map_err(|e| Error::data(manifest.display().to_string(), format!("[structure]: {e}")))?;
    Ok(GivenStructure {
        structure,
        air_density: set.manifest.section.air_density,
        chord: Some(set.manifest.section.chord),
        source: format!("[structure] of {}", set.root.display()),
    })
}

/// A bifurcation-level diagnosis as asked for (the flags of `aeroform diagnose
/// --measured-branch`, the arguments of Python's `aeroform.diagnose_branch`), before
/// anything is read.
#[derive(Debug, Clone, Copy)]
pub struct MeasuredBranchRequest<'a> {
    /// The measured diagram: a CSV table or a data-set folder of records.
    pub measured: &'a Path,
    /// The sim's aerodynamic model file (model TOML, identification.json, lag law).
    pub model: &'a Path,
    /// The given structure file; `None`: the data sets' `[structure]`.
    pub structure: Option<&'a Path>,
    /// Further data sets of free runs (still-air decays for the structure check).
    pub free: &'a [std::path::PathBuf],
    /// Measured onsets, each as `U[:F][:sub|super][:sd=SD]` (`--onset`).
    pub onsets: &'a [String],
    /// Speeds where no LCO was observed, each as `U[:PITCH[:HEAVE]]` (`--no-lco`).
    pub no_lco: &'a [String],
}

/// Everything a bifurcation-level diagnosis reads, read and checked: the caller may now
/// create its output folder, then call [`PreparedDiagram::diagnose`].
#[derive(Debug, Clone)]
pub struct PreparedDiagram {
    /// Measured points, onsets and absences (the request's rows appended to the table's).
    pub diagram: MeasuredDiagram,
    /// The nominal section: the given structure with the sim's model.
    pub section: aeroelastic::section::Section,
    /// The still-air decays of every given data set against the given structure.
    pub check: Option<super::points::StructureCheck>,
    /// How each record of a measured folder was used.
    pub uses: Vec<RecordUse>,
    /// The inputs as the report lists them (`measured: …`, `structure: …`, …).
    pub inputs: Vec<String>,
    /// Warnings of the model file (an identified model's terms outside their range, …).
    pub model_warnings: Vec<String>,
}

impl MeasuredBranchRequest<'_> {
    /// Reads and checks every input: the measured diagram ([`read_measured`]), the free
    /// runs, the onset and absence rows, the given structure ([`given_structure`], the
    /// measured records first), the model, the nominal section and the structure check of
    /// every decay.
    ///
    /// # Errors
    /// The readers' errors naming the file, line and field ([`Error::Identify`],
    /// [`Error::Aeroelastic`], [`Error::Data`]).
    pub fn prepare(&self) -> Result<PreparedDiagram> {
        let MeasuredInput {
            mut diagram,
            records,
            uses,
        } = read_measured(self.measured)?;
        let free = self
            .free
            .iter()
            .map(|f| {
                read_dataset(f).map_err(|e| Error::identify(format!("reading {}", f.display()), e))
            })
            .collect::<Result<Vec<_>>>()?;
        for o in self.onsets {
            let row = aeroelastic::branch::parse_onset_arg(o)
                .map_err(|e| Error::aeroelastic("measured onset", e))?;
            diagram.onsets.push(row);
        }
        for a in self.no_lco {
            let row = aeroelastic::branch::parse_absence_arg(a)
                .map_err(|e| Error::aeroelastic("speed without an LCO", e))?;
            diagram.absences.push(row);
        }
        let sets: Vec<&Dataset> = records.iter().chain(&free).collect();
        let given = given_structure(self.structure, &sets)?;
        let loaded = aeroelastic::files::LoadedModel::load(self.model, given.chord)
            .map_err(|e| Error::aeroelastic(format!("loading {}", self.model.display()), e))?;
        let section = aeroelastic::section::Section::new(
            given.structure,
            loaded.model.clone(),
            given.air_density,
        )
        .map_err(|e| {
            Error::aeroelastic("the nominal section (structure, model, air density)", e)
        })?;
        let decays: Vec<&Dataset> = free.iter().chain(records.iter()).collect();
        let check = super::points::structure_check(&decays, &section);
        let mut inputs = vec![
            format!("measured: {}", self.measured.display()),
            format!("structure: {}", given.source),
            format!("model: {}", self.model.display()),
        ];
        inputs.extend(free.iter().map(|f| format!("free: {}", f.root.display())));
        inputs.extend(self.onsets.iter().map(|o| format!("onset: {o}")));
        inputs.extend(self.no_lco.iter().map(|a| format!("no LCO: {a}")));
        Ok(PreparedDiagram {
            diagram,
            section,
            check,
            uses,
            inputs,
            model_warnings: loaded
                .identified
                .as_ref()
                .map(|t| t.warnings.clone())
                .unwrap_or_default(),
        })
    }
}

impl PreparedDiagram {
    /// The bifurcation-level diagnosis of the prepared inputs ([`super::diagnose_diagram`]).
    ///
    /// # Errors
    /// As [`super::diagnose_diagram`].
    pub fn diagnose(
        self,
        opts: &super::BifurcationOptions,
        version: &str,
    ) -> Result<super::BifurcationDiagnosis> {
        super::diagnose_diagram(
            &self.diagram,
            &self.section,
            self.check,
            self.uses,
            opts,
            self.inputs,
            version,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn root() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
    }

    #[test]
    fn a_table_is_read_as_a_table_and_needs_a_structure_from_somewhere() {
        let table = root().join("scenarios/bristol-spring1-lco-amplitudes.csv");
        let m = read_measured(&table).unwrap();
        assert!(m.records.is_none() && m.uses.is_empty());
        assert!(m.diagram.points.len() >= 9, "{}", m.diagram.points.len());
        // no file and no data set: refused by name, before anything else is read
        let e = given_structure(None, &[]).unwrap_err().to_string();
        assert!(e.contains("no structure"), "{e}");
        let file = root().join("scenarios/bristol-spring1.structure.toml");
        let g = given_structure(Some(&file), &[]).unwrap();
        assert!(
            g.source.ends_with("bristol-spring1.structure.toml"),
            "{}",
            g.source
        );
        assert!(g.structure.k_alpha > 0.0 && g.air_density > 0.0);
    }

    #[test]
    fn a_request_refuses_a_bad_row_naming_its_flag_and_a_missing_file_naming_it() {
        let r = root();
        let (table, model, st) = (
            r.join("scenarios/bristol-spring1-lco-amplitudes.csv"),
            r.join("scenarios/bristol-spring1.model.toml"),
            r.join("scenarios/bristol-spring1.structure.toml"),
        );
        let onsets = vec!["fast".to_string()];
        let req = MeasuredBranchRequest {
            measured: &table,
            model: &model,
            structure: Some(&st),
            free: &[],
            onsets: &onsets,
            no_lco: &[],
        };
        let e = req.prepare().unwrap_err().to_string();
        assert!(e.contains("--onset"), "{e}");
        let missing = r.join("scenarios/no-such-table.csv");
        let e = MeasuredBranchRequest {
            measured: &missing,
            onsets: &[],
            ..req
        }
        .prepare()
        .unwrap_err()
        .to_string();
        assert!(e.contains("no-such-table.csv"), "{e}");
        // a good request reads everything: the nominal section and the report's inputs
        let p = MeasuredBranchRequest { onsets: &[], ..req }
            .prepare()
            .unwrap();
        assert_eq!(p.inputs.len(), 3);
        assert!(p.inputs[1].starts_with("structure: "), "{:?}", p.inputs);
        assert!(p.check.is_none(), "a table holds no decays");
    }
}
