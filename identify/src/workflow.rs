//! A whole data set from records to regression inputs, in parallel: held whole
//! ([`prepare_dataset`]) or streamed case by case in bounded memory ([`prepare_streaming`]).

use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;

use crate::dataset::{
    open_dataset, read_case_stamped, CaseStamps, Dataset, FolderStamp, Manifest, ReadOptions,
    SampleCount,
};
use crate::ensemble::{bootstrap_subset, Ensemble, EnsembleSettings};
use crate::io::FileStamp;
use crate::pipeline::{Identification, IdentifySettings, Prepared, Progress};
use crate::preprocess::{prepare_with_report, PrepareReport, PreprocessOptions};
use crate::record::{CaseKind, NondimCase};
use crate::Result;

/// Forced cases of a data set ready for [`crate::pipeline::identify`], with the
/// preprocessing report of each (same order as the manifest's forced cases).
#[derive(Debug, Clone)]
pub struct PreparedDataset {
    /// Nondimensional regressors and targets, one per forced case.
    pub cases: Vec<NondimCase>,
    /// What preprocessing did to each case (still-air lag, velocity source, noise).
    pub reports: Vec<PrepareReport>,
}

/// Preprocesses (wind–no-wind subtraction, velocities) and nondimensionalises every forced
/// case of `dataset`, in parallel; free-response cases are skipped.
///
/// The result does not depend on the number of threads; when several cases fail, the error
/// of the first in manifest order is returned.
///
/// # Errors
/// The first error of [`prepare_with_report`] or
/// [`crate::record::PreparedCase::nondimensional`] in manifest order; each names its case.
pub fn prepare_dataset(dataset: &Dataset, opts: &PreprocessOptions) -> Result<PreparedDataset> {
    let results: Vec<Result<(NondimCase, PrepareReport)>> = dataset
        .records
        .par_iter()
        .filter(|r| r.kind == CaseKind::Forced)
        .map(|r| {
            let (prepared, report) = prepare_with_report(r, opts)?;
            Ok((
                prepared.into_nondimensional(&dataset.manifest.section)?,
                report,
            ))
        })
        .collect();
    let mut cases = Vec::with_capacity(results.len());
    let mut reports = Vec::with_capacity(results.len());
    for r in results {
        let (c, rep) = r?;
        cases.push(c);
        reports.push(rep);
    }
    Ok(PreparedDataset { cases, reports })
}

/// Batches of [`prepare_streaming`] between two releases of the threads' scratch buffers
/// ([`crate::numerics::scratch::release`]).
const RELEASE_BATCHES: usize = 4;

/// Where a forced case of a streamed data set came from: its index among the manifest's
/// cases and the stamps of its files when they were read (to read it again unchanged).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CaseSource {
    /// Index into the manifest's `cases`.
    pub index: usize,
    /// Size, modification time and fingerprint of its files as read.
    pub stamps: CaseStamps,
}

/// Seconds spent per stage of a streaming pass: `read` and `preprocess` summed over the
/// cases (thread-seconds: with several threads more than their share of the wall time),
/// `prepare` the wall time of the batches' preparation (parallel inside each batch).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StageSeconds {
    /// Reading and checking the case files (CSV parsing, sampling, units).
    pub read: f64,
    /// Preprocessing (wind − still-air subtraction, velocities, nondimensional form).
    pub preprocess: f64,
    /// The per-case preparation of the identification ([`Prepared::push`]), wall seconds.
    pub prepare: f64,
}

/// A data set prepared for identification case by case ([`prepare_streaming`]): what the
/// group stage, the metrics and the reports need of every forced case, and where to read
/// a case again when a consumer needs its samples ([`StreamedDataset::reread`]).
pub struct StreamedDataset {
    /// The data-set folder.
    pub root: PathBuf,
    /// The validated manifest (convention flipped when asked).
    pub manifest: Manifest,
    /// The forced cases prepared ([`Prepared::identify_all`] identifies them).
    pub prepared: Prepared<'static>,
    /// Per forced case (the order of `prepared`), its source files.
    pub sources: Vec<CaseSource>,
    /// Thread-seconds per stage.
    pub seconds: StageSeconds,
    stamp: FolderStamp,
    preprocess: PreprocessOptions,
}

/// Reads, preprocesses and prepares the forced cases of the data set `dir` in bounded
/// memory: batches of [`crate::pipeline::batch_size`] cases are read (one pass per file,
/// [`crate::dataset::read_case_stamped`]), preprocessed and nondimensionalised as
/// [`prepare_dataset`] does, and prepared ([`Prepared::push`]) in parallel; then their
/// samples are dropped. What is kept is O(p²) per case (p library terms), so peak memory
/// is that of one batch of cases plus the summaries, whatever the number of cases, and the
/// identification is the one [`crate::pipeline::identify`] gives on the whole set (the
/// per-case work is the same, case by case). Free-response cases are read and checked, then
/// dropped. `observer` receives [`Progress::Cases`] (forced cases done / total) on the
/// calling thread.
///
/// Every refusal of [`crate::dataset::read_dataset_with`] is kept, with its message: the
/// manifest and the case paths are checked before any case file is read, the samples of
/// all records together are bounded by `MAX_SAMPLES`, and the folder must be the same
/// folder after the last case as before the first (a set replaced while it is read is an
/// error, not a mix). Errors come in manifest order; a case file's refusal may now come
/// after an earlier case's preprocessing or preparation error (the whole set is no longer
/// read before the first case is preprocessed).
///
/// # Errors
/// As [`crate::dataset::read_dataset_with`], [`prepare_with_report`],
/// [`crate::record::PreparedCase::into_nondimensional`], [`Prepared::start`] and
/// [`Prepared::push`]; each names its file, line and field or its case.
pub fn prepare_streaming(
    dir: &Path,
    read: &ReadOptions,
    preprocess: &PreprocessOptions,
    settings: &IdentifySettings,
    observer: &dyn Fn(Progress),
) -> Result<StreamedDataset> {
    let stamp = FolderStamp::of(dir);
    let manifest = open_dataset(dir, read)?;
    let mut prepared = Prepared::start(settings)?;
    let total = manifest
        .cases
        .iter()
        .filter(|c| c.kind == CaseKind::Forced)
        .count();
    let mut samples = SampleCount::default();
    let mut sources = Vec::with_capacity(total);
    let mut seconds = StageSeconds::default();
    let indices: Vec<usize> = (0..manifest.cases.len()).collect();
    let mut batches = 0usize;
    for chunk in indices.chunks(crate::pipeline::batch_size()) {
        // (the record is dropped once preprocessed: only its sample count is kept)
        type Read = (usize, usize, CaseStamps, Option<NondimCase>, [f64; 2]);
        let done: Vec<Result<Read>> = chunk
            .par_iter()
            .map(|&i| {
                let t = Instant::now();
                let spec = &manifest.cases[i];
                let (record, stamps) = read_case_stamped(dir, &manifest, spec)?;
                let read_s = t.elapsed().as_secs_f64();
                let t = Instant::now();
                let nondim = match spec.kind {
                    CaseKind::Forced => Some(
                        prepare_with_report(&record, preprocess)?
                            .0
                            .into_nondimensional(&manifest.section)?,
                    ),
                    CaseKind::Free => None,
                };
                let samples = SampleCount::of(&record);
                drop(record);
                Ok((
                    i,
                    samples,
                    stamps,
                    nondim,
                    [read_s, t.elapsed().as_secs_f64()],
                ))
            })
            .collect();
        let mut batch = Vec::with_capacity(chunk.len());
        for r in done {
            let (i, n_samples, stamps, nondim, [read_s, pre_s]) = r?;
            samples.add_samples(dir, &manifest.cases[i], n_samples)?;
            seconds.read += read_s;
            seconds.preprocess += pre_s;
            if let Some(c) = nondim {
                batch.push(c);
                sources.push(CaseSource { index: i, stamps });
            }
        }
        let t = Instant::now();
        prepared.push(&batch)?;
        // per-case scratch buffers are reused for RELEASE_BATCHES batches, then given back
        // (docs/DECISIONS.md, round 33: kept for the whole pass they cost ≈ 40 % more peak
        // memory at the group stage; given back after every batch ≈ 0.15 s more CPU)
        batches += 1;
        if batches.is_multiple_of(RELEASE_BATCHES) {
            rayon::broadcast(|_| crate::numerics::scratch::release());
        }
        seconds.prepare += t.elapsed().as_secs_f64();
        if !batch.is_empty() {
            observer(Progress::Cases {
                done: prepared.len(),
                total,
            });
        }
    }
    // the per-case scratch buffers of every thread are not needed by the group stage
    rayon::broadcast(|_| crate::numerics::scratch::release());
    crate::numerics::scratch::release();
    stamp.check(dir)?;
    Ok(StreamedDataset {
        root: dir.to_path_buf(),
        manifest,
        prepared,
        sources,
        seconds,
        stamp,
        preprocess: preprocess.clone(),
    })
}

impl StreamedDataset {
    /// Reads the forced cases `cases` (indices into [`StreamedDataset::sources`]) again and
    /// preprocesses them as [`prepare_streaming`] did, in parallel: the samples a consumer
    /// needs after the streaming pass (a bootstrap, a figure of one case). Each file must be
    /// what it was when first read (size, modification time, content fingerprint) and the
    /// folder the same folder: a file changed in between is an error, never a mix.
    ///
    /// # Errors
    /// [`crate::Error::InvalidData`] naming the case for an index out of range;
    /// [`crate::Error::Io`] (interrupted) naming the file that changed, or the folder when
    /// it was replaced; otherwise as [`prepare_streaming`].
    pub fn reread(&self, cases: &[usize]) -> Result<Vec<NondimCase>> {
        let out: Vec<Result<NondimCase>> = cases
            .par_iter()
            .map(|&k| {
                let src = self
                    .sources
                    .get(k)
                    .ok_or_else(|| crate::Error::InvalidData {
                        case: "-".to_string(),
                        field: "case".to_string(),
                        message: format!(
                            "case index {k} is out of range (0..{})",
                            self.sources.len()
                        ),
                    })?;
                let spec = &self.manifest.cases[src.index];
                let (record, stamps) = read_case_stamped(&self.root, &self.manifest, spec)?;
                if stamps != src.stamps {
                    let (file, what) = if stamps.file != src.stamps.file {
                        (&spec.file, describe_change(&src.stamps.file, &stamps.file))
                    } else {
                        let nowind = spec.nowind_file.as_ref().unwrap_or(&spec.file);
                        (
                            nowind,
                            match (src.stamps.nowind, stamps.nowind) {
                                (Some(a), Some(b)) => describe_change(&a, &b),
                                _ => "appeared or disappeared",
                            },
                        )
                    };
                    return Err(crate::Error::io(
                        self.root.join(file),
                        std::io::Error::new(
                            std::io::ErrorKind::Interrupted,
                            format!(
                                "case `{}`: the file changed since it was first read ({what}); \
                                 the identification would mix old and new samples: run it again",
                                spec.id
                            ),
                        ),
                    ));
                }
                prepare_with_report(&record, &self.preprocess)?
                    .0
                    .into_nondimensional(&self.manifest.section)
            })
            .collect();
        self.stamp.check(&self.root)?;
        out.into_iter().collect()
    }

    /// The block-bootstrap ensemble of the identification `id` of these cases
    /// ([`crate::ensemble::bootstrap`]'s result, entry for entry), reading the cases again
    /// batch by batch ([`StreamedDataset::reread`]) so that memory stays that of one batch.
    ///
    /// # Errors
    /// As [`StreamedDataset::reread`] and [`crate::ensemble::bootstrap`].
    pub fn bootstrap(&self, id: &Identification, settings: &EnsembleSettings) -> Result<Ensemble> {
        let mut cases = Vec::with_capacity(self.sources.len());
        let all: Vec<usize> = (0..self.sources.len()).collect();
        for chunk in all.chunks(crate::pipeline::batch_size()) {
            let batch = self.reread(chunk)?;
            cases.extend(bootstrap_subset(&batch, id, settings)?);
        }
        Ok(Ensemble {
            method: "block_bootstrap".to_string(),
            settings: settings.clone(),
            cases,
        })
    }
}

fn describe_change(a: &FileStamp, b: &FileStamp) -> &'static str {
    if a.size != b.size {
        "its size differs"
    } else if a.hash != b.hash {
        "its content differs"
    } else {
        "its modification time differs"
    }
}
