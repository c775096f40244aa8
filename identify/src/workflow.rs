//! A whole data set from records to regression inputs, in parallel.

use rayon::prelude::*;

use crate::dataset::Dataset;
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
