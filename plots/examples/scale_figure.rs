//! The figure of docs/SCALE.md "Time against size": reads the CSV `scripts/scale-jobs` writes
//! (`job,axis,size,wall_s,cpu_s,peak_mb,exit`), keeps the fastest run (CPU) of each job and
//! size whose exit code is 0, and writes `scale-jobs.png` and `.svg` to DIR (docs/ keeps the
//! PNG only); prints one markdown row per job (sizes, CPU and wall times, log–log slopes,
//! peak memory).
//!
//! `cargo run --release -p plots --example scale_figure -- docs/scale/scale-jobs.csv docs/figures`

use std::collections::BTreeMap;
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 3 {
        eprintln!("usage: scale_figure SCALE.csv OUT_DIR");
        std::process::exit(2);
    }
    if let Err(e) = run(Path::new(&args[1]), Path::new(&args[2])) {
        eprintln!("scale_figure: {e}");
        std::process::exit(1);
    }
}

/// One run: size, wall, CPU, peak.
type Run = (f64, f64, f64, f64);

fn run(csv: &Path, dir: &Path) -> Result<(), String> {
    let text = std::fs::read_to_string(csv).map_err(|e| format!("{}: {e}", csv.display()))?;
    // job → (axis, size → fastest run), jobs in order of first appearance
    let mut order: Vec<String> = vec![];
    let mut jobs: BTreeMap<String, (String, BTreeMap<u64, Run>)> = BTreeMap::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let bad = |what: &str| format!("{} line {}: {what}", csv.display(), i + 1);
        if f.len() != 7 {
            return Err(bad(&format!("{} fields, expected 7", f.len())));
        }
        let num = |k: usize| {
            f[k].trim()
                .parse::<f64>()
                .map_err(|_| bad(&format!("field {} `{}` is not a number", k + 1, f[k])))
        };
        let (size, wall, cpu, peak) = (num(2)?, num(3)?, num(4)?, num(5)?);
        if f[6].trim() != "0" {
            continue;
        }
        let job = f[0].trim().to_string();
        if !jobs.contains_key(&job) {
            order.push(job.clone());
        }
        let entry = jobs
            .entry(job)
            .or_insert_with(|| (f[1].trim().to_string(), BTreeMap::new()));
        let slot = entry
            .1
            .entry(size as u64)
            .or_insert((size, wall, cpu, peak));
        if cpu < slot.2 {
            *slot = (size, wall, cpu, peak);
        }
    }
    let mut panels = vec![];
    println!(
        "| job | size axis | sizes | CPU [s] | wall [s] | peak [MB] | slope CPU | slope wall |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for job in order {
        let (axis, runs) = &jobs[&job];
        let runs: Vec<Run> = runs.values().copied().collect();
        let col = |k: usize| -> Vec<f64> { runs.iter().map(|r| [r.0, r.1, r.2, r.3][k]).collect() };
        let (size, wall, cpu, peak) = (col(0), col(1), col(2), col(3));
        let list = |v: &[f64]| {
            v.iter()
                .map(|x| format!("{x}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let slope =
            |y: &[f64]| plots::log_slope(&size, y).map_or("–".into(), |s| format!("{s:.2}"));
        println!(
            "| {job} | {axis} | {} | {} | {} | {} | {} | {} |",
            list(&size),
            list(&cpu),
            list(&wall),
            list(&peak),
            slope(&cpu),
            slope(&wall)
        );
        panels.push(plots::ScalePanel {
            job,
            x_label: format!("{axis} [-]"),
            size,
            cpu_s: cpu,
            wall_s: wall,
        });
    }
    let fig = plots::ScaleFigure {
        title: "Time against size (2 cores; fastest run of each size)".into(),
        panels,
    };
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let files = plots::save(&fig, dir, "scale-jobs").map_err(|e| e.to_string())?;
    eprintln!("wrote {}", files.png.display());
    Ok(())
}
