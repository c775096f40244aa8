//! Contract tests of every figure: PNG + SVG written, labels present, bad data → error,
//! degenerate data → no panic; the report embeds every figure.

use std::path::{Path, PathBuf};

use crate::samples;
use crate::*;

/// Decodes a PNG and returns (width, height, RGB bytes).
fn decode_png(path: &Path) -> (u32, u32, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap();
    let dec = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    assert_eq!(info.color_type, png::ColorType::Rgb);
    (info.width, info.height, buf)
}

/// Saves `fig`, checks both files and that the SVG holds every expected text.
fn check_figure<F: Figure>(fig: &F, expected: &[&str]) -> FigureFiles {
    let dir = tempfile::tempdir().unwrap();
    let files = save(fig, dir.path(), F::KIND).unwrap();
    let (w, h, rgb) = decode_png(&files.png);
    assert_eq!((w, h), fig.size(), "PNG size");
    // Dark pixels in the top 60 rows = the title was rasterised with the bundled font.
    let dark = rgb[..(w as usize * 60 * 3)]
        .chunks(3)
        .filter(|p| p.iter().all(|&c| c < 80))
        .count();
    assert!(
        dark > 200,
        "{}: title not drawn in PNG ({dark} dark pixels)",
        F::KIND
    );
    let written = std::fs::read_to_string(&files.svg).unwrap();
    assert_eq!(written, files.svg_text);
    assert!(
        written.starts_with("<svg"),
        "{}",
        &written[..40.min(written.len())]
    );
    assert!(
        !written.contains("<text"),
        "{}: the written SVG still has <text> (viewer font)",
        F::KIND
    );
    // the labels, searched in plotters' SVG before outlining
    let svg = crate::render::render_svg_text(fig).unwrap();
    for e in expected {
        // a label with subscripts is drawn run by run (crate::rich)
        match crate::rich::parse(e) {
            None => assert!(svg.contains(e), "{}: SVG lacks {e:?}", F::KIND),
            Some(runs) => {
                for r in runs {
                    let t = r.text.trim();
                    assert!(
                        t.is_empty() || svg.contains(t),
                        "{}: SVG lacks the run {t:?} of {e:?}",
                        F::KIND
                    );
                }
            }
        }
    }
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 2, "no temporary files left");
    files
}

#[test]
fn time_series_writes_png_and_svg_with_labels() {
    check_figure(
        &samples::time_series(),
        &[
            "Case A-3: forced motion and forces",
            "t [s]",
            "α [deg]",
            "h [mm]",
            "C_L [-]",
            "C_M [-]",
            "measured",
            "model (Eq. 19)",
        ],
    );
}

#[test]
fn spectrum_writes_png_and_svg_with_labels() {
    check_figure(
        &samples::spectrum(),
        &[
            "spectrum of C_M",
            "f [Hz]",
            "|C_M| amplitude [-]",
            "measured",
            "model (Eq. 19)",
            "key frequencies",
            "f_α",
            "2f_α",
            "f_α+f_h",
        ],
    );
}

#[test]
fn delta_path_writes_png_and_svg_with_labels() {
    check_figure(
        &samples::delta_path(),
        &[
            "δ path",
            "threshold δ (relative contribution) [-]",
            "terms [-]",
            "key-freq. loss [-]",
            "number of terms",
            "loss limit",
            "selected δ = ",
            "active term",
            "(Bα̇/U)³",
        ],
    );
}

#[test]
fn heatmap_writes_png_and_svg_with_labels() {
    check_figure(
        &samples::heatmap(),
        &[
            "Eq. 19 coefficients",
            "amplitude α₀ [deg]",
            "U [m/s]",
            "H1*",
            "A4*",
            "N2*",
            "inactive (term not selected)",
        ],
    );
}

#[test]
fn histogram_writes_png_and_svg_with_labels() {
    check_figure(
        &samples::histogram(),
        &[
            "Identification quality",
            "R² [-]",
            "MFWA [-]",
            "cases [-]",
            "median",
            "1 outside range",
            "1 non-finite",
        ],
    );
    // Sample MFWA values 0.85 + 0.15·√u, u = frac(0.618·i), i < 64: n = 64 shown.
    let text = crate::render::render_svg_text(&samples::histogram()).unwrap();
    assert!(text.contains("n = 64"));
}

#[test]
fn vg_writes_png_and_svg_with_labels() {
    check_figure(
        &samples::vg(),
        &[
            "V–g and V–f",
            "U [m/s]",
            "damping ratio g [-]",
            "f [Hz]",
            "heave mode",
            "pitch mode",
            "U_F = 23.4 m/s",
            "f_F = 2.343 Hz",
        ],
    );
}

#[test]
fn bifurcation_writes_png_and_svg_with_labels() {
    check_figure(
        &samples::bifurcation(),
        &[
            "hysteresis",
            "U [m/s]",
            "LCO amplitude α [deg]",
            "upward sweep",
            "downward sweep",
            "decay",
            "LCO",
            "divergent",
            "U_F = 20 m/s",
        ],
    );
}

#[test]
fn phase_writes_png_and_svg_with_labels() {
    check_figure(
        &samples::phase(),
        &[
            "Phase portrait",
            "α [deg]",
            "α̇ [deg/s]",
            "measured (free response)",
            "model",
            "start",
        ],
    );
}

#[test]
fn derivatives_writes_png_and_svg_with_labels() {
    check_figure(
        &samples::derivatives(),
        &[
            "Flutter derivatives",
            "K = Bω/U [-]",
            "H1*",
            "H4*",
            "A1*",
            "A4*",
            "configuration A",
            "configuration B",
            "flat plate (Theodorsen)",
        ],
    );
}

fn assert_no_data<F: Figure>(fig: &F, field_part: &str) {
    match render_svg(fig) {
        Err(Error::NoData { figure, field, .. }) => {
            assert_eq!(figure, F::KIND);
            assert!(field.contains(field_part), "{field:?} lacks {field_part:?}");
        }
        other => panic!("{}: expected NoData, got {other:?}", F::KIND),
    }
    assert!(render_png(fig).is_err());
}

#[test]
fn empty_or_all_nan_input_is_an_error_not_a_panic() {
    let nan = vec![f64::NAN; 5];
    let x = vec![0.0, 1.0, 2.0, 3.0, 4.0];
    assert_no_data(&TimeSeriesFigure::default(), "panels");
    let mut ts = samples::time_series();
    ts.panels[2].series[1].y = nan.clone();
    ts.panels[2].series[1].x = x.clone();
    assert_no_data(&ts, "panels[2].series[1] \"model (Eq. 19)\"");

    assert_no_data(&SpectrumFigure::default(), "series");
    let mut sp = samples::spectrum();
    sp.series[0].y = vec![0.0, -1.0, f64::NAN, 0.0, 0.0];
    sp.series[0].x = x.clone();
    assert_no_data(&sp, "positive amplitudes");

    let mut dp = samples::delta_path();
    dp.deltas = vec![f64::NAN; dp.deltas.len()];
    dp.selected = None;
    assert_no_data(&dp, "deltas");

    assert_no_data(&HeatmapGridFigure::default(), "panels");
    let mut hm = samples::heatmap();
    hm.x_values.clear();
    for p in &mut hm.panels {
        for r in &mut p.values {
            r.clear();
        }
    }
    assert_no_data(&hm, "x_values");

    assert_no_data(&HistogramFigure::default(), "panels");
    let mut hi = samples::histogram();
    hi.panels[1].values = nan.clone();
    assert_no_data(&hi, "panels[1].values");

    assert_no_data(&VgFigure::default(), "modes");
    let mut vg = samples::vg();
    vg.modes[1] = ModeBranch {
        name: "pitch mode".into(),
        u: x.clone(),
        damping: nan.clone(),
        freq: nan.clone(),
    };
    assert_no_data(&vg, "pitch mode");

    assert_no_data(&BifurcationFigure::default(), "points");
    assert_no_data(&PhasePortraitFigure::default(), "trajectories");
    let mut ph = samples::phase();
    ph.trajectories[0].x = nan.clone();
    ph.trajectories[0].y = nan.clone();
    assert_no_data(&ph, "trajectories[0]");

    assert_no_data(&DerivativeFigure::default(), "panels");
    let mut de = samples::derivatives();
    de.panels[5].points.clear();
    de.panels[5].reference_value = vec![f64::NAN; de.panels[5].reference_k.len()];
    assert_no_data(&de, "A2*");
}

#[test]
fn length_mismatch_and_bad_options_are_errors() {
    let mut ts = samples::time_series();
    ts.panels[0].series[0].y.pop();
    assert!(matches!(
        render_svg(&ts),
        Err(Error::LengthMismatch {
            left: 2048,
            right: 2047,
            ..
        })
    ));
    let mut dp = samples::delta_path();
    dp.selected = Some(99);
    let e = render_svg(&dp).unwrap_err();
    assert!(e.to_string().contains("index 99 out of range"), "{e}");
    let mut hi = samples::histogram();
    hi.panels[0].bins = 0;
    assert!(matches!(render_svg(&hi), Err(Error::InvalidInput { .. })));
    hi.panels[0].bins = 5;
    hi.panels[0].range = Some((1.0, 1.0));
    assert!(matches!(render_svg(&hi), Err(Error::InvalidInput { .. })));
    let mut hm = samples::heatmap();
    hm.panels[3].values[2].pop();
    let e = render_svg(&hm).unwrap_err();
    assert!(
        e.to_string().contains("H4*") && e.to_string().contains("values[2]"),
        "{e}"
    );
    let mut sp = samples::spectrum();
    sp.f_max = Some(f64::NAN);
    assert!(matches!(render_svg(&sp), Err(Error::InvalidInput { .. })));
    // Nothing is written when the data are unusable.
    let dir = tempfile::tempdir().unwrap();
    assert!(save(&ts, dir.path(), "x").is_err());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn degenerate_data_draws_without_panic() {
    // Single points, constant values, infinities mixed in, huge and tiny magnitudes.
    let one = |v: f64| Series::new("only", SeriesKind::Measured, vec![1.0], vec![v]);
    let ts = TimeSeriesFigure {
        title: "one point".into(),
        x_label: "t [s]".into(),
        panels: vec![
            TimePanel {
                y_label: "a".into(),
                series: vec![one(0.0)],
            },
            TimePanel {
                y_label: "b".into(),
                series: vec![Series::new(
                    "c",
                    SeriesKind::Model,
                    vec![0.0, 1.0, 2.0],
                    vec![1e300, f64::INFINITY, 1e300],
                )],
            },
        ],
    };
    render_svg(&ts).unwrap();
    render_png(&ts).unwrap();
    let sp = SpectrumFigure {
        series: vec![one(1e-30)],
        markers: vec![FreqMarker {
            freq: f64::NAN,
            label: "x".into(),
        }],
        ..Default::default()
    };
    render_png(&sp).unwrap();
    let dp = DeltaPathFigure {
        deltas: vec![0.1],
        n_terms: vec![3],
        loss: vec![0.0],
        selected: Some(0),
        loss_limit: Some(f64::NAN),
        ..Default::default()
    };
    render_png(&dp).unwrap();
    let hm = HeatmapGridFigure {
        x_values: vec![1.0],
        y_values: vec![2.0],
        panels: vec![HeatmapPanel {
            term: "N1*".into(),
            values: vec![vec![None]],
        }],
        ..Default::default()
    };
    render_png(&hm).unwrap();
    let hi = HistogramFigure {
        panels: vec![HistogramPanel {
            values: vec![0.5; 10],
            bins: 3,
            ..Default::default()
        }],
        ..Default::default()
    };
    render_png(&hi).unwrap();
    let vg = VgFigure {
        modes: vec![ModeBranch {
            name: "m".into(),
            u: vec![5.0],
            damping: vec![0.0],
            freq: vec![f64::NAN],
        }],
        flutter: Some(FlutterPoint {
            u: f64::INFINITY,
            freq: 1.0,
        }),
        ..Default::default()
    };
    render_png(&vg).unwrap();
    let bf = BifurcationFigure {
        points: vec![BifurcationPoint {
            u: 3.0,
            amplitude: f64::NAN,
            sweep: Sweep::Down,
            class: ResponseClass::Divergent,
            stop: "left_bound",
        }],
        ..Default::default()
    };
    render_png(&bf).unwrap();
    // intervals with non-finite or reversed bounds are skipped, never drawn or panicking
    let vg = VgFigure {
        modes: vec![ModeBranch {
            name: "m".into(),
            u: vec![5.0, 6.0],
            damping: vec![0.1, -0.1],
            freq: vec![1.0, 1.0],
        }],
        flutter_interval: Some(SpeedInterval {
            lower: f64::NAN,
            upper: 6.0,
            level: 0.9,
            found: 1,
            members: 2,
        }),
        ..Default::default()
    };
    render_png(&vg).unwrap();
    let bf = BifurcationFigure {
        points: vec![BifurcationPoint {
            u: 3.0,
            amplitude: 1.0,
            sweep: Sweep::Up,
            class: ResponseClass::Lco,
            stop: "",
        }],
        intervals: vec![AmplitudeInterval {
            u: 3.0,
            median: 1.0,
            lower: f64::NEG_INFINITY,
            upper: 2.0,
        }],
        flutter_interval: Some(SpeedInterval {
            lower: 4.0,
            upper: 3.0,
            level: 0.9,
            found: 1,
            members: 2,
        }),
        ..Default::default()
    };
    render_png(&bf).unwrap();
    let ph = PhasePortraitFigure {
        trajectories: vec![one(2.0)],
        ..Default::default()
    };
    render_png(&ph).unwrap();
    let de = DerivativeFigure {
        panels: vec![DerivativePanel {
            name: "H1*".into(),
            points: vec![DerivativePoints {
                label: "p".into(),
                k: vec![1.0],
                value: vec![-3.0],
                spread: vec![f64::NAN],
                interval: vec![],
            }],
            ..Default::default()
        }],
        ..Default::default()
    };
    render_png(&de).unwrap();
}

fn sample_report(dir: &Path) -> (Report, usize) {
    let mut r = Report::new("aeroform sample report");
    r.section("Summary")
        .text("Synthetic data; every figure of the plots crate once.\n\nSecond paragraph.")
        .key_values(
            "Key numbers",
            &[
                ("cases", "64"),
                ("flutter speed U_F [m/s]", "23.4"),
                ("verdict", "time_delay"),
            ],
        )
        .csv_table(
            "Per-case metrics",
            "case,R2,MFWA\nA-1,0.991,0.97\nA-2,0.985,0.95\n\"B-1, repeat\",0.62,0.81\n",
        );
    let figs: Vec<(&str, FigureFiles)> = vec![
        (
            "Time series",
            save(&samples::time_series(), dir, "time_series").unwrap(),
        ),
        (
            "Spectrum",
            save(&samples::spectrum(), dir, "spectrum").unwrap(),
        ),
        (
            "δ path",
            save(&samples::delta_path(), dir, "delta_path").unwrap(),
        ),
        (
            "Coefficient heat maps",
            save(&samples::heatmap(), dir, "heatmap").unwrap(),
        ),
        (
            "Histograms",
            save(&samples::histogram(), dir, "histogram").unwrap(),
        ),
        ("V–g / V–f", save(&samples::vg(), dir, "vg_vf").unwrap()),
        (
            "Bifurcation",
            save(&samples::bifurcation(), dir, "bifurcation").unwrap(),
        ),
        (
            "Phase portrait",
            save(&samples::phase(), dir, "phase_portrait").unwrap(),
        ),
        (
            "Derivatives",
            save(&samples::derivatives(), dir, "derivatives").unwrap(),
        ),
    ];
    r.section("Figures");
    for (c, f) in &figs {
        r.figure(*c, f);
    }
    (r, figs.len())
}

#[test]
fn report_embeds_every_figure_inline() {
    let dir = tempfile::tempdir().unwrap();
    let (r, n) = sample_report(dir.path());
    let path = dir.path().join("report.html");
    r.write(&path).unwrap();
    let html = std::fs::read_to_string(&path).unwrap();
    assert_eq!(html.matches("<svg").count(), n);
    assert_eq!(html.matches("<figcaption>").count(), n);
    for bad in ["<script", "<link", "src=", "@import", "url("] {
        assert!(!html.contains(bad), "external resource marker {bad}");
    }
    // the only links are the navigation bar's anchors into the page
    assert!(html.contains("href=\"#"));
    assert_eq!(
        html.matches("href=").count(),
        html.matches("href=\"#").count()
    );
    assert!(html.contains("<td>B-1, repeat</td>"));
    // every figure label is outlined: nothing is left to the browser's font
    assert!(
        !html.contains("<text"),
        "a figure label left to the browser font"
    );
}

fn preview_dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../preview");
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Renders every sample figure and the sample report into `preview/` (not committed) for a
/// human to look at.
#[test]
#[ignore = "writes preview files for a human to look at"]
fn render_previews() {
    let d = preview_dir();
    let (r, _) = sample_report(&d);
    r.write(&d.join("report.html")).unwrap();
}

/// `--figure-style paper`: no title, the design drawn 1.75× larger, 300 dpi in the PNG.
#[test]
fn paper_style_png_is_300_dpi_without_title() {
    let fig = samples::vg();
    let (w, h) = fig.size();
    let bytes = crate::with_figure_style(crate::FigureStyle::Paper, || render_png(&fig)).unwrap();
    let dec = png::Decoder::new(std::io::Cursor::new(&bytes));
    let reader = dec.read_info().unwrap();
    let info = reader.info();
    assert_eq!(
        (info.width, info.height),
        (
            (w as f64 * 1.75).round() as u32,
            (h as f64 * 1.75).round() as u32
        )
    );
    let dims = info.pixel_dims.expect("pHYs chunk");
    assert_eq!(dims.unit, png::Unit::Meter);
    assert!(
        (dims.xppu as f64 * 0.0254 - 300.0).abs() < 0.1,
        "{}",
        dims.xppu
    );
    // the screen style of the same figure is unchanged on this thread afterwards
    let screen = render_png(&fig).unwrap();
    let dec = png::Decoder::new(std::io::Cursor::new(&screen));
    let r = dec.read_info().unwrap();
    assert_eq!((r.info().width, r.info().height), (w, h));
    assert!(r.info().pixel_dims.is_none());
}

/// `--figure-style paper`: a PDF beside PNG and SVG, one page of the paper size (1200 design
/// pixels = 7 in = 504 pt), the bundled font embedded; panel letters on multi-panel figures
/// and none in the screen style.
#[test]
fn paper_style_writes_pdf_with_panel_letters() {
    let fig = samples::vg(); // V–g over V–f: two panels
    let (w, h) = fig.size();
    let dir = tempfile::tempdir().unwrap();
    let files =
        crate::with_figure_style(crate::FigureStyle::Paper, || save(&fig, dir.path(), "vg"))
            .unwrap();
    let pdf_path = files.pdf.expect("paper style writes a PDF");
    let pdf = std::fs::read(&pdf_path).unwrap();
    assert!(pdf.starts_with(b"%PDF-"), "not a PDF");
    let text = String::from_utf8_lossy(&pdf);
    // MediaBox in points: design px × 72 / (300 / 1.75)
    let to_pt = |px: u32| px as f64 * 72.0 * 1.75 / 300.0;
    let mb = text
        .split("/MediaBox [")
        .nth(1)
        .and_then(|t| t.split(']').next())
        .expect("a MediaBox");
    let v: Vec<f64> = mb.split_whitespace().map(|x| x.parse().unwrap()).collect();
    assert!((v[2] - v[0] - to_pt(w)).abs() < 0.5, "width {mb}");
    assert!((v[3] - v[1] - to_pt(h)).abs() < 0.5, "height {mb}");
    assert!(text.contains("DejaVu"), "bundled font not embedded");
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 3, "png, svg and pdf, no temporary files");
    let paper =
        crate::with_figure_style(crate::FigureStyle::Paper, || crate::render_svg_text(&fig))
            .unwrap();
    assert!(
        paper.contains("(a)") && paper.contains("(b)"),
        "panel letters"
    );
    let screen = crate::render_svg_text(&fig).unwrap();
    assert!(!screen.contains("(a)"), "no panel letters on screen");
    // the screen style writes no PDF
    let dir = tempfile::tempdir().unwrap();
    assert!(save(&fig, dir.path(), "vg").unwrap().pdf.is_none());
}
