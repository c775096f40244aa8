//! Cost of drawing one figure: plotters' SVG (text left to the viewer), the written SVG
//! (text as glyph outlines, `plots::render_svg`), the paper PDF and the PNG, side by side
//! on the same 4-panel time series (2048 samples per series).

use criterion::{criterion_group, criterion_main, Criterion};

fn render(c: &mut Criterion) {
    let fig = plots::samples::time_series();
    let mut g = c.benchmark_group("render_time_series");
    g.sample_size(20);
    g.bench_function("svg_text", |b| {
        b.iter(|| plots::render_svg_text(&fig).unwrap())
    });
    g.bench_function("svg_outlined", |b| {
        b.iter(|| plots::render_svg(&fig).unwrap())
    });
    g.bench_function("pdf", |b| b.iter(|| plots::render_pdf(&fig).unwrap()));
    g.bench_function("png", |b| b.iter(|| plots::render_png(&fig).unwrap()));
    g.finish();
}

criterion_group!(benches, render);
criterion_main!(benches);
