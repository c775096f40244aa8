//! Every figure of aeroform (plotters, bundled font) and the HTML report.
