//! Every figure of aeroform (plotters, bundled font) and the HTML report.
//!
//! Each figure is a plain data struct implementing [`Figure`]; [`save`] renders it to PNG
//! (bitmap) and SVG with the same drawing code and writes both atomically, returning
//! [`FigureFiles`] (paths and the SVG text). Text is drawn with the bundled DejaVu Sans
//! (registered once as `"sans-serif"`); no system font is used. Non-finite values are
//! skipped; a figure with nothing finite to draw is an [`Error::NoData`], never a panic.
//! [`Report`] builds a self-contained HTML page with inline SVG figures;
//! [`study_report::render_all`] draws every figure and the report of a study output folder.

#![warn(missing_docs)]

pub mod adapters;
pub mod bifurcation_report;
pub mod diagnosis_report;
pub mod error;
pub mod figures;
mod pdf;
pub mod render;
pub mod report;
mod report_parts;
pub mod rich;
pub mod scaled;
pub mod study_report;
pub mod style;
mod vector;

/// Synthetic sample figures (tests, previews and the render benchmark; not an API).
#[doc(hidden)]
pub mod samples;

pub use bifurcation_report::write_bifurcation_outputs;
pub use diagnosis_report::{
    diagnosis_report, diagnosis_section, save_diagnosis_figures, write_diagnosis_outputs,
    DiagnosisFigure,
};
pub use error::{Error, Result};
pub use figures::bifurcation::{
    AmplitudeInterval, BifurcationFigure, BifurcationPoint, ResponseClass, Sweep,
};
pub use figures::branch_comparison::{BranchComparisonFigure, ComparisonDofPanel, DiagramLayer};
pub use figures::branch_diagram::{BranchCurve, BranchDiagramFigure, DiagramPoint};
pub use figures::comparison::{ComparisonFigure, ComparisonPanel};
pub use figures::delta_path::DeltaPathFigure;
pub use figures::derivatives::{DerivativeFigure, DerivativePanel, DerivativePoints};
pub use figures::flutter::{FlutterPoint, ModeBranch, SpeedInterval, VgFigure};
pub use figures::gap_heatmap::{GapHeatmapFigure, GapHeatmapPanel};
pub use figures::heatmap::{diverging, HeatmapGridFigure, HeatmapPanel};
pub use figures::histogram::{HistogramFigure, HistogramPanel};
pub use figures::library::{LibraryCell, LibraryFigure};
pub use figures::phase::PhasePortraitFigure;
pub use figures::ranking::{
    RankingBar, RankingFigure, RankingPanel, ShareBar, ShareSegment, SharesFigure,
};
pub use figures::residual_spectra::{ResidualSpectraFigure, SpectraPanel};
pub use figures::scale::{log_slope, ScaleFigure, ScalePanel};
pub use figures::spectrum::{FreqMarker, SpectrumFigure};
pub use figures::time_series::{TimePanel, TimeSeriesFigure};
pub use figures::{Series, SeriesKind};
pub use render::{render_pdf, render_png, render_svg, render_svg_text, save, Figure, FigureFiles};
pub use report::{anchor, column_label, escape_html, Report};
pub use scaled::{figure_style, set_figure_style, with_figure_style, FigureStyle};

#[cfg(test)]
mod tests;
