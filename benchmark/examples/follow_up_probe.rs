//! Investigation probe (round 34): one set's follow-up at the force and free-response levels.
use benchmark::bench::{draw_specs_from, shapes_truths, CampaignShape};
use benchmark::blind::{follow_up_forced, generate, BlindEffect};
use diagnose::pipeline::{diagnose, DiagnoseOptions};
use diagnose::report::Diagnosis;

fn case_gaps(d: &Diagnosis) {
    for l in &d.levels {
        if l.level != diagnose::effect::Level::Aerodynamic {
            continue;
        }
        let mut v: Vec<_> = l.cases.iter().collect();
        v.sort_by(|a, b| {
            (b.before * b.before - b.after * b.after)
                .total_cmp(&(a.before * a.before - a.after * a.after))
        });
        for c in v.iter().take(6) {
            println!(
                "      case {} U {:.2} A {:.1} before/noise {:.2} after/noise {:.2}",
                c.id,
                c.wind_speed,
                c.amplitude,
                c.before / c.noise_level,
                c.after / c.noise_level
            );
        }
    }
}

fn dump(tag: &str, d: &Diagnosis) {
    println!(
        "  [{tag}] verdict {} conf {:.2}",
        d.verdict.effect.name(),
        d.verdict.confidence
    );
    for l in &d.levels {
        println!(
            "    level {:?} before {:.4} noise {:.4} sig {} stat {:.2} thr {:.2}",
            l.level, l.before, l.noise_level, l.significant_gap, l.gap_statistic, l.gap_threshold
        );
        for c in &l.candidates {
            let n = c.effect.name();
            if ["vortex_shedding", "time_delay", "buffeting", "added_mass"].contains(&n)
                || c.significant
            {
                println!(
                    "      cand {n} before {:.4} after {:.4} shrink {:.3} stat {:.2} thr {:.2} sig {} params {:?} fail {:?}",
                    c.before, c.after, c.shrink, c.statistic, c.threshold, c.significant,
                    c.parameters, c.failure
                );
            }
        }
    }
}

fn main() {
    let idx: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let specs = draw_specs_from(330, 2026, &shapes_truths());
    for i in idx {
        let mut spec = specs[i].clone();
        let shape = CampaignShape::draw_with_physics(spec.seed);
        spec.shape = Some(shape.clone());
        let base = benchmark::blind::BlindScenario::default();
        let sc = shape.scenario(&base).unwrap();
        let form = shape.form();
        let mut dopts = DiagnoseOptions::new(spec.seed);
        dopts.system.simulate = false;
        dopts.seed = spec.seed;
        dopts.force.seed = spec.seed;
        dopts.system.seed = spec.seed;
        let set = generate(spec.truth, spec.strength, form, spec.seed, &sc).unwrap();
        println!(
            "set {i} truth {} strength {:.3} params {:?}",
            spec.truth, spec.strength, set.truth.parameters
        );
        println!(
            "  forced: {} cases, {:.1} s at {} Hz; speeds {:?}; noise {:?}",
            set.forced.records.len(),
            sc.forced_duration,
            sc.forced_rate,
            sc.campaign.wind_speeds,
            sc.noise
        );
        let d = diagnose(&set.forced, Some(&set.free), &dopts, "b").unwrap();
        dump("before", &d);
        case_gaps(&d);
        let Some(plan) = &d.follow_up else {
            println!("  no plan");
            continue;
        };
        for r in &plan.rows {
            println!(
                "  row {} {} f {:.3}/{:.3} U {:?} A {:?} x{:?} T {:?} disc {:?} {:?}",
                r.rank,
                r.configuration.name,
                r.configuration.freq_pitch,
                r.configuration.freq_heave,
                r.wind_speeds,
                r.amplitudes_deg,
                r.repeats,
                r.record_duration_s,
                r.discrimination,
                r.reason
            );
        }
        let cases = plan.cases();
        let f2 = follow_up_forced(
            spec.truth,
            spec.strength,
            form,
            spec.seed,
            &sc,
            &set.forced,
            &cases,
        )
        .unwrap();
        let d2 = diagnose(&f2, Some(&set.free), &dopts, "b2").unwrap();
        dump("after", &d2);
        case_gaps(&d2);
        let twin = generate(BlindEffect::None, 0.0, form, spec.seed, &sc).unwrap();
        let t2 = follow_up_forced(
            BlindEffect::None,
            0.0,
            form,
            spec.seed,
            &sc,
            &twin.forced,
            &cases,
        )
        .unwrap();
        let td = diagnose(&t2, Some(&twin.free), &dopts, "t2").unwrap();
        dump("twin after", &td);
    }
}
