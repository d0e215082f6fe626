//! `fracture bench ab`: interleaved A/B runs of the single throughput run against a baseline
//! binary, and the cachegrind instruction count of one run (`bench throughput
//! --instructions`). Both run `fracture bench --json` as child processes, so the baseline can be
//! any older build of this command (one that predates `--kernel` and `--case` gets only the
//! arguments it knows: the no-crack block, its own default arithmetic).

use std::path::Path;
use std::process::Command;

use anyhow::Context;

use super::command::{BenchArgs, CaseArg, KernelArg};
use crate::report::{csv_line, markdown_table, write_file};

/// One run of a `fracture bench --json` child.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Sample {
    /// `baseline` or `this`.
    pub side: &'static str,
    /// Pair number (from 1).
    pub pair: usize,
    /// Particle-steps per second the child reported.
    pub particle_steps_per_second: f64,
    /// The child's solver version.
    pub solver_version: String,
    /// 1-minute load average before the run.
    pub load_average: f64,
}

/// The A/B report.
#[derive(Debug, Clone, serde::Serialize)]
pub struct AbReport {
    /// Where and when.
    pub machine: super::Machine,
    /// The baseline binary.
    pub baseline: String,
    /// Arguments both sides ran with.
    pub args: Vec<String>,
    /// Every run, in the order they ran.
    pub samples: Vec<Sample>,
    /// Median of the baseline's runs (particle-steps/s).
    pub baseline_median: f64,
    /// Median of this binary's runs.
    pub this_median: f64,
    /// this_median / baseline_median.
    pub ratio_of_medians: f64,
    /// Median over the pairs of this / baseline.
    pub median_of_pair_ratios: f64,
}

fn load_average() -> f64 {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|x| x.parse().ok()))
        .unwrap_or(f64::NAN)
}

/// The arguments of the single run that every build of `fracture bench` understands.
fn common_args(a: &BenchArgs) -> Vec<String> {
    vec![
        "bench".into(),
        "--json".into(),
        "--cell-size".into(),
        a.cell_size.to_string(),
        "--particles-per-cell".into(),
        a.particles_per_cell.to_string(),
        "--steps".into(),
        a.steps.to_string(),
        "--warmup".into(),
        a.warmup.to_string(),
        "--threads".into(),
        a.threads.to_string(),
    ]
}

/// The name clap gives a value of `--case` or `--kernel` on the command line.
fn arg_name(v: impl clap::ValueEnum) -> String {
    v.to_possible_value()
        .map_or_else(String::new, |p| p.get_name().to_string())
}

/// `--case` (where not the default) and its `--history-every`: what a baseline that knows
/// `--case` must get too.
fn case_args(a: &BenchArgs, case: CaseArg) -> Vec<String> {
    if case == CaseArg::NoCrack {
        return Vec::new();
    }
    vec![
        "--case".into(),
        arg_name(case),
        "--history-every".into(),
        a.history_every.to_string(),
    ]
}

/// The case arguments and `--kernel`: what this build adds to the common ones.
fn own_args(a: &BenchArgs, kernel: KernelArg, case: CaseArg) -> Vec<String> {
    let mut v = case_args(a, case);
    v.extend(["--kernel".into(), arg_name(kernel)]);
    v
}

/// Run `bin args` and read the particle-steps/s and solver version of its JSON.
fn run_child(bin: &Path, args: &[String]) -> anyhow::Result<(f64, String)> {
    let o = Command::new(bin)
        .args(args)
        .output()
        .with_context(|| format!("running {}", bin.display()))?;
    if !o.status.success() {
        anyhow::bail!(
            "{} {} failed ({}): {}",
            bin.display(),
            args.join(" "),
            o.status,
            String::from_utf8_lossy(&o.stderr).trim()
        );
    }
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).with_context(|| {
        format!(
            "{}: its output is not the JSON of `bench --json`",
            bin.display()
        )
    })?;
    let rate = v["particle_steps_per_second"]
        .as_f64()
        .ok_or_else(|| anyhow::anyhow!("{}: no particle_steps_per_second", bin.display()))?;
    let version = v["solver_version"].as_str().unwrap_or("?").to_string();
    Ok((rate, version))
}

/// Run `pairs` interleaved pairs (the baseline first in odd pairs, this binary first in even
/// ones, so a drift of the machine's speed does not favour one side); print and write the
/// report.
pub fn run(baseline: &Path, a: &BenchArgs, out: Option<&Path>) -> anyhow::Result<AbReport> {
    if a.pairs == 0 {
        anyhow::bail!("--pairs 0: bench ab needs at least one pair");
    }
    if !baseline.is_file() {
        anyhow::bail!("--baseline {}: no such file", baseline.display());
    }
    let me = std::env::current_exe().context("the path of this fracture binary")?;
    let machine = super::Machine::now();
    let common = common_args(a);
    let mut this_args = common.clone();
    this_args.extend(own_args(a, a.kernel, a.case));
    // An older baseline may not know --case: it then fails with its own message.
    let mut base_args = common.clone();
    base_args.extend(case_args(a, a.case));
    let mut samples = Vec::new();
    let mut ratios = Vec::new();
    for pair in 1..=a.pairs {
        let order: [(&'static str, &Path, &Vec<String>); 2] = if pair % 2 == 1 {
            [
                ("baseline", baseline, &base_args),
                ("this", &me, &this_args),
            ]
        } else {
            [
                ("this", &me, &this_args),
                ("baseline", baseline, &base_args),
            ]
        };
        let mut got = [f64::NAN; 2];
        for (side, bin, args) in order {
            let load = load_average();
            let (rate, version) = run_child(bin, args)?;
            eprintln!(
                "pair {pair}: {side} {:.4e} particle-steps/s (load {load:.2})",
                rate
            );
            got[usize::from(side == "this")] = rate;
            samples.push(Sample {
                side,
                pair,
                particle_steps_per_second: rate,
                solver_version: version,
                load_average: load,
            });
        }
        ratios.push(got[1] / got[0]);
    }
    let side = |s: &str| -> Vec<f64> {
        samples
            .iter()
            .filter(|x| x.side == s)
            .map(|x| x.particle_steps_per_second)
            .collect()
    };
    let baseline_median = super::median(&side("baseline"));
    let this_median = super::median(&side("this"));
    let report = AbReport {
        machine,
        baseline: baseline.display().to_string(),
        args: this_args,
        samples,
        baseline_median,
        this_median,
        ratio_of_medians: this_median / baseline_median,
        median_of_pair_ratios: super::median(&ratios),
    };
    let md = markdown(&report);
    #[allow(clippy::print_stdout)]
    {
        println!("{md}");
    }
    if let Some(out) = out {
        write_file(out, "ab.md", &md)?;
        write_file(out, "ab.json", &serde_json::to_string_pretty(&report)?)?;
        let mut csv =
            String::from("pair,side,particle_steps_per_second,solver_version,load_average\n");
        for s in &report.samples {
            csv.push_str(&csv_line(&[
                s.pair.to_string(),
                s.side.into(),
                format!("{:.6e}", s.particle_steps_per_second),
                s.solver_version.clone(),
                format!("{:.2}", s.load_average),
            ]));
        }
        write_file(out, "ab.csv", &csv)?;
    }
    Ok(report)
}

fn markdown(r: &AbReport) -> String {
    let mut s = format!(
        "# A/B throughput\n\n`fracture bench ab`: {} interleaved pairs of `fracture {}` against \
         the baseline `{}`; {}.\n\n",
        r.samples.len() / 2,
        r.args.join(" "),
        r.baseline,
        r.machine.describe()
    );
    let pairs = r.samples.len() / 2;
    let rows: Vec<Vec<String>> = (1..=pairs)
        .map(|p| {
            let get = |side: &str| {
                r.samples
                    .iter()
                    .find(|x| x.pair == p && x.side == side)
                    .map_or(f64::NAN, |x| x.particle_steps_per_second)
            };
            let (b, t) = (get("baseline"), get("this"));
            vec![
                p.to_string(),
                format!("{:.2} M", b / 1e6),
                format!("{:.2} M", t / 1e6),
                format!("{:.3}", t / b),
            ]
        })
        .collect();
    s.push_str(&markdown_table(
        &[
            "pair",
            "baseline (particle-steps/s)",
            "this",
            "this / baseline",
        ],
        &rows,
    ));
    s.push_str(&format!(
        "\nMedians: baseline {:.2} M, this {:.2} M particle-steps/s; ratio of the medians \
         {:.3}, median of the pair ratios {:.3}.\n",
        r.baseline_median / 1e6,
        r.this_median / 1e6,
        r.ratio_of_medians,
        r.median_of_pair_ratios
    ));
    s
}

/// Instructions per particle-step of one case (one thread, `cell_size` cells), counted by
/// valgrind's cachegrind on two child runs, with and without `steps` timed steps after one
/// warm-up step (the set-up and the first, unfused step cancel out). `Ok(None)` where valgrind
/// is not installed.
pub fn instructions_per_particle_step(
    case: CaseArg,
    cell_size: f64,
    steps: u64,
    kernel: KernelArg,
) -> anyhow::Result<Option<f64>> {
    if Command::new("valgrind").arg("--version").output().is_err() {
        return Ok(None);
    }
    let me = std::env::current_exe().context("the path of this fracture binary")?;
    let count = |n: u64| -> anyhow::Result<(f64, f64)> {
        let mut args: Vec<String> = vec![
            "--tool=cachegrind".into(),
            "--cache-sim=no".into(),
            "--cachegrind-out-file=/dev/null".into(),
            me.display().to_string(),
        ];
        let a = BenchArgs::for_instructions(case, cell_size, n, kernel);
        args.extend(common_args(&a));
        args.extend(own_args(&a, kernel, case));
        let o = Command::new("valgrind")
            .args(&args)
            .output()
            .context("running valgrind")?;
        let err = String::from_utf8_lossy(&o.stderr);
        if !o.status.success() {
            anyhow::bail!(
                "valgrind {} failed ({}): {}",
                args.join(" "),
                o.status,
                err.trim()
            );
        }
        let refs = parse_i_refs(&err)
            .ok_or_else(|| anyhow::anyhow!("no `I refs` line in valgrind's output: {err}"))?;
        let v: serde_json::Value = serde_json::from_slice(&o.stdout)
            .context("the JSON of the counted `bench --json` run")?;
        let particles = v["particles"].as_f64().unwrap_or(f64::NAN);
        Ok((refs, particles))
    };
    let (with, particles) = count(steps)?;
    let (without, _) = count(0)?;
    Ok(Some((with - without) / (particles * steps.max(1) as f64)))
}

/// The total of cachegrind's `I refs:` line (`==123== I   refs:      841,234,567`).
pub fn parse_i_refs(stderr: &str) -> Option<f64> {
    stderr.lines().find_map(|l| {
        let rest = l.split("==").last()?.trim();
        let rest = rest.strip_prefix('I')?.trim_start();
        let num = rest.strip_prefix("refs:")?.trim();
        num.replace(',', "").parse::<f64>().ok()
    })
}

#[cfg(test)]
mod tests {
    use super::parse_i_refs;

    #[test]
    fn reads_cachegrinds_instruction_total() {
        let err = "==4242== Cachegrind, a cache and branch-prediction profiler\n\
                   ==4242== \n==4242== I   refs:      841,234,567\n";
        assert_eq!(parse_i_refs(err), Some(841_234_567.0));
        assert_eq!(parse_i_refs("==1== I refs: 12\n"), Some(12.0));
        assert_eq!(parse_i_refs("==1== D   refs: 12\n"), None);
    }
}
