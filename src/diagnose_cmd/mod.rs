//! `aeroform diagnose`: where predictions and measurements differ, which unmodelled effect
//! causes it and how far the gap shrinks once it is added (`diagnosis.json`, figures,
//! `diagnosis.html`); `--blind N` runs the withheld-effect benchmark instead.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use aeroelastic::files::{LoadedModel, StructureFile};
use anyhow::Context;
use benchmark::bench::{acceptance_lines, confusion_markdown, BlindReport, STRONG_RATIO};
use benchmark::bench_run::{run_blind, BlindOptions};
use diagnose::pipeline::{diagnose, diagnose_free, merge_free, DiagnoseOptions};
use diagnose::Diagnosis;
use identify::dataset::read_dataset;
use identify::io::write_atomic;

mod args;
mod measured_branch;

pub use args::DiagnoseArgs;
use crate::progress::CountBar;

/// Keeps freed memory in the process for the diagnosis (glibc only): its levels allocate and
/// free columns of tens of thousands of samples in loops, and glibc's default thresholds
/// (128 kB, dynamic) hand each back to the kernel, which faults the same pages in again. With
/// allocations up to 32 MB (glibc's largest mmap threshold) served from the heap and the heap
/// top trimmed only beyond 1 GB, job 1 of `scripts/profile` spends 0.30–0.34 s instead of
/// 0.52–0.55 s in the kernel, peak 351 → 359–367 MB, output identical (issue 43 row 1,
/// docs/DECISIONS.md round 32). Not set for `identify`, whose bounded-memory bars are
/// measured with the defaults.
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets two allocator parameters; it is called before any thread of
    // this command allocates and returns 0 (ignored: the defaults stay) when refused.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
    }
}

/// Runs `aeroform diagnose`.
pub fn run(args: &DiagnoseArgs) -> anyhow::Result<()> {
    keep_freed_memory();
    // clap's `requires = "blind"` is void when a data set is given: `--blind` conflicts
    // with it, and clap drops a requirement that conflicts with a present argument
    if args.blind.is_none() {
        let flag = [
            ("--shard", args.shard.is_some()),
            ("--shapes", args.shapes),
            ("--branch-level", args.branch_level),
            ("--misgiven-structure", args.misgiven_structure),
        ]
        .into_iter()
        .find_map(|(f, given)| given.then_some(f));
        if let Some(f) = flag {
            return Err(crate::exit::Usage(format!(
                "{f} needs --blind N: it belongs to the withheld-effect benchmark, not to the \
                 diagnosis of a data set"
            ))
            .into());
        }
    }
    if let Some(n) = args.blind {
        let n = aeroform::limits::count("--blind", n, aeroform::limits::MAX_BLIND_SETS)?;
        let out = args
            .out
            .clone()
            .unwrap_or_else(|| PathBuf::from("out/blind"));
        if let Some(s) = &args.shard {
            return blind_shard(n, args.seed, args.shapes, s, &out);
        }
        if args.branch_level {
            let bench = benchmark::branch_bench::BranchBenchOptions {
                misgiven_structure: args.misgiven_structure,
                hold_given: false,
                jacobian: args.fit.into(),
            };
            return measured_branch::blind(n, args.seed, &bench, &out, args.force);
        }
        return blind(n, args.seed, args.shapes, args.follow_up, &out, args.force);
    }
    if let Some(m) = &args.measured_branch {
        return measured_branch::run(args, m);
    }
    if args.model.is_some() && args.free.is_empty() {
        return Err(crate::exit::Usage(
            "--model needs --free FREE (free-response records) or --measured-branch".into(),
        )
        .into());
    }
    if args.structure.is_some() && args.free.is_empty() {
        return Err(crate::exit::Usage(
            "--structure needs --free FREE or --measured-branch".into(),
        )
        .into());
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out/diagnosis"));
    // before the inputs are read (`OutDir::begin` checks it again)
    crate::outdir::refuse_overlap(&out, "--out", &args.inputs())?;
    let free_sets = args
        .free
        .iter()
        .map(|f| read_dataset(f).with_context(|| format!("reading {}", f.display())))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let free = if free_sets.is_empty() {
        None
    } else {
        Some(merge_free(&free_sets)?)
    };
    let mut opts = DiagnoseOptions::new(args.seed);
    let mut chord = free.as_ref().map(|f| f.manifest.section.chord);
    if let Some(s) = &args.structure {
        let sf = StructureFile::read(s).with_context(|| format!("reading {}", s.display()))?;
        if !sf.nonlinear.is_empty() {
            crate::exit::refuse!(
                "{}: the diagnosis's nominal structure is linear (stiffness terms, freeplay and \
                 friction are what the catalogue looks for); remove them",
                s.display()
            );
        }
        chord = sf.chord.or(chord);
        opts.system.structure = Some(sf.linear);
    }
    // Every input is read and checked before the output folder is touched.
    enum Input {
        Free(LoadedModel),
        Forced(identify::dataset::Dataset),
    }
    let input = match (&args.dataset, &args.model, &free) {
        (_, Some(m), Some(_)) => Input::Free(
            LoadedModel::load(m, chord).with_context(|| format!("loading {}", m.display()))?,
        ),
        (Some(d), None, _) => {
            let mut sets =
                vec![read_dataset(d).with_context(|| format!("reading {}", d.display()))?];
            for e in &args.forced_extra {
                let extra = read_dataset(e).with_context(|| format!("reading {}", e.display()))?;
                let (a, b) = (&sets[0].manifest.section, &extra.manifest.section);
                if (a.air_density - b.air_density).abs() > 1e-9 * a.air_density
                    || (a.span - b.span).abs() > 1e-9 * a.span
                {
                    crate::exit::refuse!(
                        "--forced-extra {}: its section (span {} m, air density {} kg/m³) is \
                         not FORCED's (span {} m, air density {} kg/m³)",
                        e.display(),
                        b.span,
                        b.air_density,
                        a.span,
                        a.air_density
                    );
                }
                sets.push(extra);
            }
            Input::Forced(if sets.len() == 1 {
                sets.pop().expect("one set")
            } else {
                merge_free(&sets)?
            })
        }
        _ => crate::exit::refuse!(
            "give a forced data-set folder, --free FREE --model M, or --blind N"
        ),
    };
    let dir = crate::outdir::OutDir::begin(&out, "diagnose", args.force, &args.inputs())?;
    let t = std::time::Instant::now();
    let version = crate::version();
    let spinner =
        crate::progress::Spinner::new("diagnose", "held-out folds, candidates and verdict");
    let diag = match (&input, &free) {
        (Input::Free(loaded), Some(free)) => diagnose_free(free, &loaded.model, &opts, &version),
        (Input::Forced(forced), _) => diagnose(forced, free.as_ref(), &opts, &version),
        (Input::Free(_), None) => unreachable!("a model is only read with free data"),
    };
    spinner.finish();
    let diag = diag?;
    let secs = t.elapsed().as_secs_f64();
    write_json(&dir.path().join("diagnosis.json"), &diag)?;
    let plan = &diag.follow_up;
    if let Some(plan) = plan {
        write_atomic(&dir.path().join(FOLLOW_UP_FILE), plan.to_toml()?.as_bytes())?;
    }
    let files = plots::write_diagnosis_outputs(&diag, dir.path())?;
    dir.commit()?;
    print_diagnosis(&diag, secs);
    if let Some(plan) = plan {
        crate::ui::say!(
            "follow-up: {} forced cases in {} row(s) would cover the free runs outside the \
             forced range: {} (aeroform tunnel forced --campaign-file)",
            plan.cases().len(),
            plan.rows.len(),
            out.join(FOLLOW_UP_FILE).display()
        );
    }
    crate::ui::say!(
        "wrote {} and {} figure/report files to {}",
        out.join("diagnosis.json").display(),
        files.len(),
        out.display()
    );
    crate::ui::document(&diag)
}

/// The follow-up campaign plan `diagnose` writes beside diagnosis.json when free runs lie
/// outside the forced range (issue 42 item 4).
const FOLLOW_UP_FILE: &str = "follow_up.campaign.toml";

fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> anyhow::Result<()> {
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    write_atomic(path, text.as_bytes())?;
    Ok(())
}

fn print_diagnosis(d: &Diagnosis, secs: f64) {
    crate::ui::say!(
        "verdict: {} (level {}, confidence {:.2})",
        d.verdict.effect,
        d.verdict.level.name(),
        d.verdict.confidence
    );
    crate::ui::say!("  {}", d.verdict.reason);
    crate::ui::say!(
        "gap ({}): before {:.4}, after {:.4}, noise level {:.4}, shrink {:.1} % (excess {:.1} %)",
        d.gap.metric,
        d.gap.before,
        d.gap.after,
        d.gap.noise_level,
        100.0 * d.gap.shrink,
        100.0 * d.gap.excess_shrink
    );
    for l in &d.levels {
        crate::ui::say!(
            "level {}: held-out gap {:.4} vs noise {:.4} ({}significant)",
            l.level.name(),
            l.before,
            l.noise_level,
            if l.significant_gap { "" } else { "not " }
        );
        for c in l.candidates.iter().take(4) {
            crate::ui::say!(
                "    {:<17} after {:.4}  shrink {:>6.1} %  {}",
                c.effect.name(),
                c.after,
                100.0 * c.shrink,
                if c.significant { "significant" } else { "" }
            );
        }
    }
    crate::ui::say!("diagnosed in {secs:.2} s");
}

fn blind(
    n: usize,
    seed: u64,
    shapes: bool,
    follow_up: bool,
    out: &Path,
    force: bool,
) -> anyhow::Result<()> {
    let dir = crate::outdir::OutDir::begin(out, "diagnose --blind", force, &[])?;
    let mut opts = BlindOptions::new(n, seed);
    opts.shapes = shapes;
    opts.follow_up = follow_up;
    let bar = CountBar::new("blind", n);
    let wrong = AtomicUsize::new(0);
    let t = std::time::Instant::now();
    let report = run_blind(&opts, &|o| {
        if !o.correct() {
            wrong.fetch_add(1, Ordering::Relaxed);
        }
        bar.tick(format!("{} → {}", o.spec.truth, o.verdict_name()));
    });
    bar.finish();
    let secs = t.elapsed().as_secs_f64();
    write_json(&dir.path().join("blind.json"), &report)?;
    let text = blind_text(&report, secs);
    write_atomic(&dir.path().join("confusion.md"), text.as_bytes())?;
    dir.commit()?;
    if !crate::ui::silent() {
        print!("{text}");
    }
    crate::ui::say!(
        "wrote {} and {}",
        out.join("blind.json").display(),
        out.join("confusion.md").display()
    );
    crate::ui::document(&report)
}

/// One shard of the benchmark as a part document (`benchmark::sweep`).
fn blind_shard(
    n: usize,
    seed: u64,
    shapes: bool,
    shard: &str,
    out: &Path,
) -> anyhow::Result<()> {
    let (i, k) = benchmark::sweep::parse_shard(shard)?;
    let spec =
        benchmark::sweep::SweepSpec::Blind(benchmark::sweep::BlindSweep { n, seed, shapes });
    spec.validate("--blind")?;
    let path = out.join(format!("blind.part-{i}-of-{k}.json"));
    crate::outdir::refuse_symlink(out, "--out")?;
    let _out = crate::outdir::SharedDir::begin(out, &[&path], &[])?;
    let part = spec.run_shard(i, k)?;
    write_json(&path, &part)?;
    crate::ui::say!("shard {i}/{k} of {n} sets; wrote {}", path.display());
    crate::ui::document(&part)
}

/// The printed and saved summary of a benchmark.
fn blind_text(r: &BlindReport, secs: f64) -> String {
    let s = &r.summary;
    let mut t = format!(
        "# Withheld-effect benchmark\n\n{} data sets, master seed {}, {} failed, {:.1} s \
         ({:.2} s per set on {} threads).\n\n",
        s.n,
        r.seed,
        s.failed,
        secs,
        s.mean_seconds,
        rayon::current_num_threads()
    );
    t.push_str(&format!(
        "## Strong sets (true gap ≥ {STRONG_RATIO}× the noise-level gap) and every effect-free set\n\n"
    ));
    t.push_str(&confusion_markdown(
        &r.truth_labels,
        &r.verdict_labels,
        &r.confusion_strong,
    ));
    t.push_str("\n## All sets\n\n");
    t.push_str(&confusion_markdown(
        &r.truth_labels,
        &r.verdict_labels,
        &r.confusion_all,
    ));
    t.push_str("\n## Acceptance\n\n");
    for l in acceptance_lines(s) {
        t.push_str(&format!("- {l}\n"));
    }
    if !r.per_shape.is_empty() {
        t.push_str(
            "\n## Per campaign shape\n\n| shape | sets | failed | top-1 strong | \
             none/extrapolation | unexplained (outside) | median shrink |\n\
             |---|---:|---:|---:|---:|---:|---:|\n",
        );
        let p = |x: f64, n: usize| {
            if n == 0 {
                "–".to_string()
            } else {
                format!("{:.0} % of {n}", 100.0 * x)
            }
        };
        for (class, s) in &r.per_shape {
            t.push_str(&format!(
                "| {class} | {} | {} | {} | {} | {} | {} |\n",
                s.n,
                s.failed,
                p(s.catalogue_top1, s.catalogue_strong),
                p(s.none_rate, s.none_sets),
                p(s.outside_unexplained, s.outside_strong),
                if s.median_shrink_named.is_finite() {
                    format!("{:.0} %", 100.0 * s.median_shrink_named)
                } else {
                    "–".into()
                }
            ));
        }
    }
    let followed: Vec<_> = r
        .outcomes
        .iter()
        .filter(|o| o.follow_up.is_some())
        .collect();
    if !followed.is_empty() {
        let right = followed
            .iter()
            .filter(|o| o.follow_up_correct() == Some(true))
            .count();
        let right_before = followed.iter().filter(|o| o.correct()).count();
        // the effect visible once the runs are covered (its twin given the same tests)
        let strong: Vec<_> = followed
            .iter()
            .filter(|o| {
                o.follow_up
                    .as_ref()
                    .is_some_and(|f| f.gap_ratio >= STRONG_RATIO)
                    || o.spec.truth == benchmark::blind::BlindEffect::None
            })
            .collect();
        let strong_right = strong
            .iter()
            .filter(|o| o.follow_up_correct() == Some(true))
            .count();
        let cases: usize = followed
            .iter()
            .filter_map(|o| o.follow_up.as_ref())
            .map(|f| f.cases)
            .sum();
        t.push_str(&format!(
            "\n## Follow-up of the `extrapolation` verdicts (recommended forced tests run on the truth)\n\n\
             {} sets followed up ({} forced cases added in all): right after {} ({:.0} %), right before {}; \
             strong once covered (gap ratio ≥ {STRONG_RATIO} after the follow-up) or effect-free: {} of {} right.\n",
            followed.len(),
            cases,
            right,
            100.0 * right as f64 / followed.len() as f64,
            right_before,
            strong_right,
            strong.len()
        ));
    }
    t.push_str(
        "\n## Per effect (strong sets)\n\n| effect | correct | strong sets |\n|---|---:|---:|\n",
    );
    for (e, c, n) in &s.per_effect {
        t.push_str(&format!("| {e} | {c} | {n} |\n"));
    }
    let mut weak: Vec<String> = r
        .outcomes
        .iter()
        .filter(|o| {
            o.error.is_none()
                && (o.strong() || o.spec.truth == benchmark::blind::BlindEffect::None)
                && !o.correct()
        })
        .map(|o| {
            format!(
                "- set {} (seed {}): {} at strength {:.2}, gap ratio {:.1} → {} (confidence {:.2})",
                o.spec.index,
                o.spec.seed,
                o.spec.truth,
                o.spec.strength,
                o.gap_ratio,
                o.verdict_name(),
                o.confidence
            )
        })
        .collect();
    if !weak.is_empty() {
        t.push_str("\n## Wrong verdicts on strong sets\n\n");
        weak.truncate(40);
        for w in weak {
            t.push_str(&w);
            t.push('\n');
        }
    }
    let errors: Vec<&str> = r
        .outcomes
        .iter()
        .filter_map(|o| o.error.as_deref())
        .collect();
    if !errors.is_empty() {
        t.push_str("\n## Failed sets\n\n");
        for e in errors.iter().take(20) {
            t.push_str(&format!("- {e}\n"));
        }
    }
    t
}
