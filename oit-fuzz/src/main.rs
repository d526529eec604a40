//! `oit-fuzz`: a fuzz harness for oit's front door on stable Rust — OBJ loading, scene
//! expressions and every command's options — in the manner of cargo-fuzz, without nightly.
//!
//! Contract: `oit-fuzz [--target obj|scene|args|all] [--execs N] [--seconds S] [--seed N]` runs
//! the committed corpus (`tests/fuzz/corpus/<target>/`, one input a file) once, then inputs
//! mutated from it and generated with `arbitrary`, until N executions or S seconds, and prints
//! executions per second and a summary per target. It exits 0 when no execution panicked, hung
//! (ran over `--timeout`) or allocated past `--max-mb` (one request or the total live), and 1
//! otherwise, with every failing input saved in `--crashes` (with its message beside it, `.log`).
//! `--replay` runs the corpus alone. See `tests/fuzz/README.md`.
//!
//! How: the supervisor (this process) runs workers (`--jobs`, each a process of this binary)
//! whose global allocator counts live bytes and refuses requests past the limit. A worker writes
//! each input to its state file before running it, so that when a worker hangs (the supervisor
//! kills it) or dies (a refused allocation aborts it, as a stack overflow does), the supervisor
//! knows the input, saves it, and starts the worker again after it. Panics the worker catches
//! and saves itself.

mod alloc;
mod dictionary;
mod generate;
mod gltf;
mod hostile;
mod mutate;
mod targets;
mod worker;

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitCode, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use clap::Parser;

use crate::worker::{Failure, Stats, TargetStats};

#[global_allocator]
static ALLOCATOR: alloc::Counting = alloc::Counting;

/// Where the corpus is unless `--corpus` says otherwise.
const DEFAULT_CORPUS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/fuzz/corpus");

/// The model file limit the workers run under (`OIT_MAX_MODEL_BYTES`): files the fuzzer names
/// are the corpus's own, and a larger limit would only let a stray path be read at length.
const WORKER_MAX_MODEL_BYTES: &str = "4194304";

/// What is fuzzed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// OBJ text.
    Obj,
    /// Scene expressions.
    Scene,
    /// `oit`'s arguments, one a line.
    Args,
    /// The harness's own check: inputs that fail on purpose.
    Selftest,
    /// glTF files (GLB or `.gltf` JSON).
    Gltf,
}

impl Target {
    /// Every target, in the order of the state file's index.
    pub const ALL: [Target; 5] = [Target::Obj, Target::Scene, Target::Args, Target::Selftest, Target::Gltf];

    /// The name, which is also the corpus folder's.
    pub fn name(self) -> &'static str {
        match self {
            Target::Obj => "obj",
            Target::Scene => "scene",
            Target::Args => "args",
            Target::Selftest => "selftest",
            Target::Gltf => "gltf",
        }
    }

    /// The extension of saved inputs.
    pub fn extension(self) -> &'static str {
        match self {
            Target::Obj => "obj",
            Target::Args => "args",
            Target::Scene | Target::Selftest => "txt",
            Target::Gltf => "glb",
        }
    }

    /// The longest input made: an OBJ of 1 MiB holds a face of some 100,000 corners; scene
    /// expressions and command lines are short; a glTF seed may be a real scene of megabytes
    /// (mutated only up to [`gltf::POOL_MAX_BYTES`]).
    pub fn max_len(self) -> usize {
        match self {
            Target::Obj => 1 << 20,
            Target::Scene => 4096,
            Target::Args => 8192,
            Target::Selftest => 64,
            Target::Gltf => 16 << 20,
        }
    }

    fn parse_list(list: &str) -> Result<Vec<Target>, String> {
        if list == "all" {
            return Ok(vec![Target::Obj, Target::Scene, Target::Args, Target::Gltf]);
        }
        list.split(',')
            .map(|name| {
                Target::ALL
                    .into_iter()
                    .find(|t| t.name() == name.trim())
                    .ok_or_else(|| format!("unknown target '{name}': use obj, scene, args, gltf or all"))
            })
            .collect()
    }
}

/// oit's fuzz harness: OBJ loading, scene expressions and every command's options, watched for
/// panics, hangs and unbounded allocation.
#[derive(Parser, Debug)]
#[command(name = "oit-fuzz")]
struct Options {
    /// What to fuzz: obj, scene, args, gltf, a comma-separated list, or all.
    #[arg(long, default_value = "all")]
    target: String,
    /// Executions in all, the corpus's replay included [default: 10000 unless --seconds is given].
    #[arg(long)]
    execs: Option<u64>,
    /// Seconds to run at most [default: no limit unless --execs is not given either].
    #[arg(long)]
    seconds: Option<f64>,
    /// The random seed: the same seed, corpus and --jobs make the same inputs in the same order.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Worker processes run side by side (the executions are shared among them).
    #[arg(long, default_value_t = 1)]
    jobs: u64,
    /// Run the corpus once and nothing else.
    #[arg(long)]
    replay: bool,
    /// The corpus: a folder of obj/, scene/ and args/ folders of one input a file.
    #[arg(long, default_value = DEFAULT_CORPUS)]
    corpus: PathBuf,
    /// Where failing inputs are written (with a .log of what happened beside each).
    #[arg(long, default_value = "fuzz-crashes")]
    crashes: PathBuf,
    /// Seconds one execution may take before it counts as a hang.
    #[arg(long, default_value_t = 10.0)]
    timeout: f64,
    /// MiB a worker may hold live at once; an allocation past it fails the execution.
    #[arg(long, default_value_t = 256)]
    max_mb: usize,
    /// Render a small frame from one accepted input in this many (0: never).
    #[arg(long, default_value_t = 16)]
    render_every: u64,
    /// Also write the summary as JSON to this file.
    #[arg(long)]
    summary: Option<PathBuf>,
    /// No progress lines.
    #[arg(long)]
    quiet: bool,
    /// Write the gltf target's seed files into this folder and exit (the committed
    /// tests/fuzz/corpus/gltf/ is written so).
    #[arg(long, value_name = "DIR")]
    write_gltf_seeds: Option<PathBuf>,
    /// Internal: run as a worker.
    #[arg(long, hide = true)]
    worker: bool,
    /// Internal: executions an earlier worker of this job made.
    #[arg(long, hide = true, default_value_t = 0)]
    start: u64,
    /// Internal: the worker's state file.
    #[arg(long, hide = true)]
    state: Option<PathBuf>,
    /// Internal: the worker's stats file.
    #[arg(long, hide = true)]
    stats: Option<PathBuf>,
    /// Internal: the worker's scratch folder.
    #[arg(long, hide = true)]
    scratch: Option<PathBuf>,
}

/// The bytes of a worker's stderr kept for the report: the end of it.
const TAIL: usize = 16 << 10;

/// A worker process and the end of its stderr.
struct Running {
    child: Child,
    tail: Arc<Mutex<Vec<u8>>>,
    drain: std::thread::JoinHandle<()>,
}

/// One job: a share of the executions, run by one worker after another (a new one after each
/// that hangs or dies).
struct JobState {
    dir: PathBuf,
    budget: u64,
    seed: u64,
    /// Executions made by the workers that ended.
    done: u64,
    restarts: u32,
    running: Option<Running>,
    last_index: Option<u64>,
    last_change: Instant,
    stats: Vec<Stats>,
    failures: Vec<Failure>,
}

/// Workers started again after a failure, per job, before it gives up.
const MAX_RESTARTS: u32 = 100;

fn main() -> ExitCode {
    let options = Options::parse();
    if let Some(dir) = &options.write_gltf_seeds {
        return match gltf::write_seeds(dir) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {}: {e}", dir.display());
                ExitCode::from(2)
            }
        };
    }
    let targets = match Target::parse_list(&options.target) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let (execs, seconds) = match (options.execs, options.seconds) {
        (None, None) => (10_000, f64::INFINITY),
        (Some(n), None) => (n, f64::INFINITY),
        (None, Some(s)) => (u64::MAX, s),
        (Some(n), Some(s)) => (n, s),
    };
    if options.worker {
        return run_worker(&options, targets, execs, seconds);
    }
    supervise(&options, &targets, execs, seconds)
}

fn run_worker(o: &Options, targets: Vec<Target>, execs: u64, seconds: f64) -> ExitCode {
    let (Some(state), Some(stats), Some(scratch)) = (&o.state, &o.stats, &o.scratch) else {
        eprintln!("error: a worker needs --state, --stats and --scratch");
        return ExitCode::from(2);
    };
    let job = worker::Job {
        targets,
        execs,
        seconds,
        seed: o.seed,
        replay: o.replay,
        start: o.start,
        corpus: o.corpus.clone(),
        crashes: o.crashes.clone(),
        state: state.clone(),
        stats: stats.clone(),
        scratch: scratch.clone(),
        max_bytes: o.max_mb.saturating_mul(1 << 20),
        render_every: o.render_every,
    };
    match worker::run(&job) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: worker: {e}");
            ExitCode::from(3)
        }
    }
}

fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

/// Starts the worker of `job`, after `job.done` executions, until `deadline`.
fn spawn(
    o: &Options,
    corpus: &Path,
    crashes: &Path,
    job: &JobState,
    deadline: Instant,
) -> std::io::Result<Running> {
    let seconds = deadline.saturating_duration_since(Instant::now()).as_secs_f64().min(1e9);
    let mut cmd = Command::new(std::env::current_exe()?);
    cmd.arg("--worker")
        .args(["--target", &o.target])
        .args(["--execs", &job.budget.to_string()])
        .args(["--seconds", &seconds.to_string()])
        .args([
            "--seed",
            &job.seed.wrapping_add(u64::from(job.restarts).wrapping_mul(0x9e37_79b9)).to_string(),
        ])
        .args(["--start", &job.done.to_string()])
        .args(["--max-mb", &o.max_mb.to_string()])
        .args(["--render-every", &o.render_every.to_string()])
        .arg("--corpus")
        .arg(corpus)
        .arg("--crashes")
        .arg(crashes)
        .arg("--state")
        .arg(job.dir.join("state"))
        .arg("--stats")
        .arg(job.dir.join("stats.json"))
        .arg("--scratch")
        .arg(job.dir.join("scratch"));
    if o.replay {
        cmd.arg("--replay");
    }
    // the corpus's relative paths (obj/star-10000.obj) resolve from its folder
    cmd.current_dir(corpus)
        .env("OIT_MAX_MODEL_BYTES", WORKER_MAX_MODEL_BYTES)
        .env_remove("OIT_MODELS")
        .env_remove("OIT_ADAPTER")
        .env("RUST_BACKTRACE", "0")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn()?;
    let mut stderr = child.stderr.take().expect("stderr is piped");
    let tail = Arc::new(Mutex::new(Vec::new()));
    let keep = tail.clone();
    let drain = std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while let Ok(n) = stderr.read(&mut buf) {
            if n == 0 {
                break;
            }
            if let Ok(mut t) = keep.lock() {
                t.extend_from_slice(&buf[..n]);
                if t.len() > 2 * TAIL {
                    let cut = t.len() - TAIL;
                    t.drain(..cut);
                }
            }
        }
    });
    Ok(Running { child, tail, drain })
}

/// What a worker's death says about the input it was running.
fn classify(stderr: &str, status: std::process::ExitStatus) -> (&'static str, String) {
    let last = |needle: &str| stderr.lines().rev().find(|l| l.contains(needle)).map(str::to_string);
    if let Some(line) = last("memory allocation of") {
        return ("alloc", format!("{line} (the limit is --max-mb)"));
    }
    if let Some(line) = last("overflowed its stack") {
        return ("stack", line);
    }
    let lines: Vec<&str> = stderr.lines().rev().take(3).collect();
    (
        "crash",
        format!("worker ended with {status}: {}", lines.into_iter().rev().collect::<Vec<_>>().join(" | ")),
    )
}

/// Reads and removes a worker's stats file.
fn take_stats(dir: &Path) -> Option<Stats> {
    let path = dir.join("stats.json");
    let stats = std::fs::read_to_string(&path).ok().and_then(|t| serde_json::from_str(&t).ok());
    let _ = std::fs::remove_file(&path);
    stats
}

fn supervise(o: &Options, targets: &[Target], execs: u64, seconds: f64) -> ExitCode {
    let corpus = match o.corpus.canonicalize() {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: corpus {}: {e}", o.corpus.display());
            return ExitCode::from(2);
        }
    };
    let crashes = absolute(&o.crashes);
    let work = std::env::temp_dir().join(format!("oit-fuzz-{}", std::process::id()));
    let started = Instant::now();
    let deadline = started.checked_add(Duration::from_secs_f64(seconds.min(1e9))).unwrap_or(started);
    let jobs = o.jobs.max(1);
    let mut states: Vec<JobState> = (0..jobs)
        .map(|n| JobState {
            dir: work.join(format!("job-{n}")),
            budget: if execs == u64::MAX { u64::MAX } else { execs / jobs + u64::from(n < execs % jobs) },
            seed: o.seed.wrapping_mul(1_000_003).wrapping_add(n),
            done: 0,
            restarts: 0,
            running: None,
            last_index: None,
            last_change: Instant::now(),
            stats: Vec::new(),
            failures: Vec::new(),
        })
        .collect();
    for s in &mut states {
        let _ = std::fs::create_dir_all(&s.dir);
        match spawn(o, &corpus, &crashes, s, deadline) {
            Ok(r) => s.running = Some(r),
            Err(e) => {
                eprintln!("error: cannot start a worker: {e}");
                return ExitCode::from(2);
            }
        }
    }
    let timeout = Duration::from_secs_f64(o.timeout.max(0.01));
    let mut last_progress = Instant::now();
    while states.iter().any(|s| s.running.is_some()) {
        std::thread::sleep(Duration::from_millis(20));
        for s in &mut states {
            poll(o, &corpus, &crashes, s, deadline, timeout);
        }
        if !o.quiet && last_progress.elapsed() > Duration::from_secs(10) {
            last_progress = Instant::now();
            let made: u64 = states
                .iter()
                .map(|s| s.done.max(worker::read_index(&s.dir.join("state")).map_or(s.done, |i| i)))
                .sum();
            let failures: usize = states.iter().map(|s| s.failures.len()).sum::<usize>()
                + states.iter().flat_map(|s| &s.stats).map(|st| st.failures.len()).sum::<usize>();
            let secs = started.elapsed().as_secs_f64();
            eprintln!(
                "oit-fuzz: {made} executions, {:.0}/s, {failures} failures, {secs:.0} s",
                made as f64 / secs
            );
        }
    }
    let _ = std::fs::remove_dir_all(&work);
    report(o, targets, &states, started.elapsed().as_secs_f64())
}

/// Watches one job's worker: its end (a success, or a death to report and a new worker), or an
/// execution past the timeout (a hang: the worker is killed).
fn poll(o: &Options, corpus: &Path, crashes: &Path, s: &mut JobState, deadline: Instant, timeout: Duration) {
    let Some(running) = &mut s.running else { return };
    let state_path = s.dir.join("state");
    let (status, hung) = match running.child.try_wait() {
        Ok(Some(status)) => (status, false),
        Ok(None) => {
            let index = worker::read_index(&state_path);
            if index != s.last_index {
                s.last_index = index;
                s.last_change = Instant::now();
                return;
            }
            if index.is_none() || s.last_change.elapsed() < timeout {
                return;
            }
            let _ = running.child.kill();
            match running.child.wait() {
                Ok(status) => (status, true),
                Err(_) => return,
            }
        }
        Err(_) => return,
    };
    let Some(running) = s.running.take() else { return };
    let _ = running.drain.join();
    let stderr = running.tail.lock().map(|t| String::from_utf8_lossy(&t).into_owned()).unwrap_or_default();
    let stats = take_stats(&s.dir);
    let counted: u64 = stats.iter().flat_map(|st| st.targets.values()).map(|t| t.execs).sum();
    s.stats.extend(stats);
    if status.success() && !hung {
        return;
    }
    let Some((index, target, input)) = worker::read_state(&state_path) else {
        s.failures.push(Failure {
            kind: "crash".into(),
            target: "-".into(),
            file: PathBuf::new(),
            message: format!("a worker ended with {status} before its first execution: {stderr}"),
        });
        return;
    };
    let (kind, message) = if hung {
        ("hang", format!("ran over {:.1} s (--timeout)", timeout.as_secs_f64()))
    } else {
        classify(&stderr, status)
    };
    let file = worker::save(crashes, kind, target, &input, &message);
    eprintln!("oit-fuzz: {kind} on {} input {}: {message}", target.name(), file.display());
    // the executions since the worker's last stats (the failing one among them) count too; they
    // are put down to the failing one's target
    let missed = (index + 1).saturating_sub(s.done).saturating_sub(counted).max(1);
    let missed = TargetStats { execs: missed, ..Default::default() };
    s.stats
        .push(Stats { targets: BTreeMap::from([(target.name().to_string(), missed)]), failures: Vec::new() });
    s.failures.push(Failure { kind: kind.into(), target: target.name().into(), file, message });
    s.done = index + 1;
    s.restarts += 1;
    s.last_index = None;
    s.last_change = Instant::now();
    let _ = std::fs::remove_file(&state_path);
    if s.done < s.budget && Instant::now() < deadline && s.restarts <= MAX_RESTARTS {
        match spawn(o, corpus, crashes, s, deadline) {
            Ok(r) => s.running = Some(r),
            Err(e) => eprintln!("oit-fuzz: cannot start a worker again: {e}"),
        }
    }
}

/// The summary: per target and in all, as a table (and JSON with `--summary`); the exit code.
fn report(o: &Options, targets: &[Target], states: &[JobState], seconds: f64) -> ExitCode {
    let mut totals: BTreeMap<String, TargetStats> = BTreeMap::new();
    let mut failures: Vec<Failure> = Vec::new();
    for s in states {
        failures.extend(s.failures.iter().cloned());
        for stats in &s.stats {
            failures.extend(stats.failures.iter().cloned());
            for (name, t) in &stats.targets {
                let sum = totals.entry(name.clone()).or_default();
                sum.execs += t.execs;
                sum.replayed += t.replayed;
                sum.generated += t.generated;
                sum.accepted += t.accepted;
                sum.refused += t.refused;
                sum.rendered += t.rendered;
                sum.panics += t.panics;
                sum.signatures = sum.signatures.max(t.signatures);
                sum.corpus = sum.corpus.max(t.corpus);
                sum.peak_bytes = sum.peak_bytes.max(t.peak_bytes);
                if t.slowest_ms > sum.slowest_ms {
                    sum.slowest_ms = t.slowest_ms;
                    sum.slowest_input = t.slowest_input.clone();
                }
            }
        }
    }
    let execs: u64 = totals.values().map(|t| t.execs).sum();
    let names: Vec<&str> = targets.iter().map(|t| t.name()).collect();
    let mut text = format!(
        "oit-fuzz: {execs} executions in {seconds:.1} s ({:.0}/s) on {} (seed {}, {} job{}{}); {} failure{}\n",
        execs as f64 / seconds.max(1e-9),
        names.join(", "),
        o.seed,
        o.jobs.max(1),
        if o.jobs > 1 { "s" } else { "" },
        if o.replay { ", corpus replay only" } else { "" },
        failures.len(),
        if failures.len() == 1 { "" } else { "s" },
    );
    text.push_str(&format!(
        "{:<8} {:>9} {:>8} {:>9} {:>9} {:>9} {:>8} {:>10} {:>6} {:>11} {:>9}\n",
        "target",
        "execs",
        "replayed",
        "generated",
        "accepted",
        "refused",
        "rendered",
        "signatures",
        "pool",
        "slowest ms",
        "peak MiB"
    ));
    for (name, t) in &totals {
        text.push_str(&format!(
            "{name:<8} {:>9} {:>8} {:>9} {:>9} {:>9} {:>8} {:>10} {:>6} {:>11.1} {:>9.1}\n",
            t.execs,
            t.replayed,
            t.generated,
            t.accepted,
            t.refused,
            t.rendered,
            t.signatures,
            t.corpus,
            t.slowest_ms,
            t.peak_bytes as f64 / f64::from(1u32 << 20)
        ));
    }
    for (name, t) in &totals {
        text.push_str(&format!("slowest {name}: {}\n", t.slowest_input));
    }
    for f in &failures {
        text.push_str(&format!("FAILURE {} on {}: {} ({})\n", f.kind, f.target, f.message, f.file.display()));
    }
    if targets.contains(&Target::Args) {
        let (commands, options) = dictionary::Vocabulary::new().counts();
        text.push_str(&format!(
            "args drew on {commands} commands and {options} options (oit-cli's clap definition)\n"
        ));
    }
    print!("{text}");
    if let Some(path) = &o.summary {
        let json = serde_json::json!({
            "executions": execs,
            "seconds": seconds,
            "per_second": execs as f64 / seconds.max(1e-9),
            "seed": o.seed,
            "jobs": o.jobs,
            "targets": totals,
            "failures": failures,
        });
        if let Err(e) = std::fs::write(path, serde_json::to_string_pretty(&json).unwrap_or_default()) {
            eprintln!("error: {}: {e}", path.display());
        }
    }
    if failures.is_empty() { ExitCode::SUCCESS } else { ExitCode::FAILURE }
}
