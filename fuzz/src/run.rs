//! The fuzz loop: mutate, execute, classify, keep, save.
//!
//! Inputs run either in-process (under [`std::panic::catch_unwind`], with a
//! wall-clock check after each input) or, better, in a worker child process
//! (a re-exec of the `sornav-fuzz` binary with `--worker TARGET`) that gets
//! inputs over a pipe. The worker's address space is capped (`ulimit -v`,
//! through `/bin/sh`), so an allocation beyond the memory bound aborts the
//! worker instead of the machine; the parent kills a worker that exceeds the
//! time bound, saves the input, and starts a new worker.
//!
//! Worker protocol: the parent writes `u32` little-endian length + bytes; the
//! worker answers one status byte (0 `Ok`, 1 `Err`, 2 panic) then `u32`
//! length + the message (the error or panic text).

use std::collections::HashSet;
use std::io::{Read, Write};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::time::{Duration, Instant};

use crate::mutate::Mutator;
use crate::targets::{Outcome, Target};

/// Most corpus entries kept per target (seeds included).
pub const MAX_CORPUS: usize = 2_000;
/// Most outcome kinds remembered per target (bounds the runner's memory).
pub const MAX_KINDS: usize = 1_000_000;
/// Most distinct crashes recorded per run (later ones are only counted).
pub const MAX_RECORDED_CRASHES: usize = 20;

/// Errors of the runner itself (never of the parsers under test).
#[derive(Debug, thiserror::Error)]
pub enum FuzzError {
    /// A file or pipe operation failed.
    #[error("{what}: {source}")]
    Io {
        /// What was being done.
        what: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The worker process broke the protocol.
    #[error("worker protocol: {0}")]
    Protocol(String),
}

fn io(what: impl Into<String>) -> impl FnOnce(std::io::Error) -> FuzzError {
    let what = what.into();
    move |source| FuzzError::Io { what, source }
}

/// How a run is configured.
#[derive(Debug, Clone)]
pub struct Options {
    /// Wall-clock length of the run.
    pub duration: Duration,
    /// Seed of the mutator.
    pub seed: u64,
    /// Time bound per input.
    pub timeout: Duration,
    /// Peak resident memory bound of a worker (MiB; 0: none), checked
    /// after every input that took over 5 ms (large allocations take
    /// longer); the worker's address space is capped at four times the
    /// bound, so an allocation far past it fails at once. In-process runs
    /// cannot bound memory.
    pub memory_mb: u64,
    /// The `sornav-fuzz` binary to re-exec as a worker; `None` runs inputs
    /// in-process.
    pub worker_exe: Option<PathBuf>,
    /// Where the corpus grown by the run is written (`DIR/<target>/`).
    pub corpus_out: Option<PathBuf>,
    /// Where crashing inputs are written (`DIR/<target>/`).
    pub crashes: Option<PathBuf>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            duration: Duration::from_secs(60),
            seed: 0,
            timeout: Duration::from_secs(2),
            memory_mb: 512,
            worker_exe: None,
            corpus_out: None,
            crashes: None,
        }
    }
}

/// How an input crashed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CrashKind {
    /// The parser panicked.
    Panic,
    /// The input took longer than the time bound.
    Timeout,
    /// The worker process died (abort, failed allocation, signal).
    Died,
    /// The worker's peak resident memory exceeded the memory bound.
    Memory,
}

/// One crashing input.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Crash {
    /// How it crashed.
    pub kind: CrashKind,
    /// Panic message, elapsed time or exit status.
    pub message: String,
    /// The input, as lowercase hex.
    pub hex: String,
    /// Where it was saved, if it was.
    pub file: Option<PathBuf>,
    #[serde(skip)]
    /// The input.
    pub input: Vec<u8>,
}

/// The figures of one target's run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Report {
    /// Target name.
    pub target: String,
    /// Inputs executed.
    pub inputs: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Inputs per second.
    pub inputs_per_s: f64,
    /// Crashing inputs (all, including unrecorded duplicates).
    pub crashes: u64,
    /// Inputs the parser accepted.
    pub accepted: u64,
    /// Seeds the run started from.
    pub seeds: usize,
    /// Corpus size at the end.
    pub corpus: usize,
    /// Distinct outcome kinds seen (accepted, and each error message shape;
    /// at most [`MAX_KINDS`]).
    pub outcome_kinds: usize,
    /// Workers started (1 + restarts after crashes; 0 in-process).
    pub workers: u64,
    /// The distinct crashes (at most [`MAX_RECORDED_CRASHES`]).
    pub crash_list: Vec<Crash>,
}

/// The result of executing one input.
enum Exec {
    /// The parser returned.
    Done(Outcome),
    /// The input crashed.
    Crashed(CrashKind, String),
}

/// Runs `target` for `options.duration`.
///
/// # Errors
/// [`FuzzError`] when a worker cannot be started or talked to, or a file
/// cannot be written; crashes of the parser are reported, not errors.
pub fn run(target: &Target, options: &Options) -> Result<Report, FuzzError> {
    let seeds = (target.seeds)();
    let mut corpus: Vec<Vec<u8>> = seeds.clone();
    if corpus.is_empty() {
        corpus.push(Vec::new());
    }
    let n_seeds = corpus.len();
    let mut mutator = Mutator::new(options.seed, target.max_len);
    let mut kinds: HashSet<u64> = HashSet::new();
    let mut crash_kinds: HashSet<(CrashKind, String)> = HashSet::new();
    let mut report = Report {
        target: target.name.to_string(),
        inputs: 0,
        seconds: 0.0,
        inputs_per_s: 0.0,
        crashes: 0,
        accepted: 0,
        seeds: n_seeds,
        corpus: 0,
        outcome_kinds: 0,
        workers: 0,
        crash_list: Vec::new(),
    };
    let mut worker: Option<Worker> = None;
    let start = Instant::now();
    let mut next_seed = 0;
    while start.elapsed() < options.duration {
        // Every seed runs once unchanged, then mutations of the corpus.
        let input = if next_seed < n_seeds {
            next_seed += 1;
            corpus[next_seed - 1].clone()
        } else {
            let i = mutator.below(corpus.len());
            mutator.mutate(&corpus, i, target.dictionary)
        };
        let exec = match &options.worker_exe {
            None => exec_in_process(target, &input, options.timeout),
            Some(exe) => {
                if worker.is_none() {
                    worker = Some(Worker::start(exe, target.name, options.memory_mb)?);
                    report.workers += 1;
                }
                let w = worker.as_mut().expect("started above");
                let e = w.exec(&input, options.timeout)?;
                if matches!(
                    e,
                    Exec::Crashed(CrashKind::Timeout | CrashKind::Died | CrashKind::Memory, _)
                ) && let Some(mut w) = worker.take()
                {
                    w.stop();
                }
                e
            }
        };
        report.inputs += 1;
        match exec {
            Exec::Done(outcome) => {
                if outcome.is_ok() {
                    report.accepted += 1;
                }
                let kind = signature(&outcome);
                if kinds.len() < MAX_KINDS && kinds.insert(kind) && corpus.len() < MAX_CORPUS {
                    corpus.push(input);
                }
            }
            Exec::Crashed(kind, message) => {
                report.crashes += 1;
                let shape = (kind, shape_of(&message));
                if report.crash_list.len() < MAX_RECORDED_CRASHES && crash_kinds.insert(shape) {
                    let file = match &options.crashes {
                        Some(dir) => Some(save(dir, target.name, "crash", &input)?),
                        None => None,
                    };
                    report.crash_list.push(Crash {
                        kind,
                        message,
                        hex: hex(&input),
                        file,
                        input,
                    });
                }
            }
        }
    }
    if let Some(mut w) = worker.take() {
        w.stop();
    }
    if let Some(dir) = &options.corpus_out {
        for input in &corpus[n_seeds.min(corpus.len())..] {
            save(dir, target.name, "input", input)?;
        }
    }
    report.seconds = start.elapsed().as_secs_f64();
    report.inputs_per_s = report.inputs as f64 / report.seconds.max(1e-9);
    report.corpus = corpus.len();
    report.outcome_kinds = kinds.len();
    Ok(report)
}

/// The outcome's kind: "ok", or the first five words of the error with
/// numbers and quoted text blurred, so that one error kind with different
/// values counts once (hashed: the set stays small over long runs).
fn signature(outcome: &Outcome) -> u64 {
    match outcome {
        Ok(()) => 0,
        Err(e) => {
            let shape = shape_of(e);
            let words: Vec<&str> = shape.split_whitespace().take(5).collect();
            fnv(words.join(" ").as_bytes()) | 1
        }
    }
}

fn shape_of(message: &str) -> String {
    let mut out = String::new();
    let mut quoted = false;
    for c in message.chars() {
        match c {
            '`' | '"' | '\'' => {
                quoted = !quoted;
                out.push('"');
            }
            _ if quoted => {}
            '0'..='9' => {
                if !out.ends_with('#') {
                    out.push('#');
                }
            }
            _ => out.push(c),
        }
        if out.len() >= 64 {
            break;
        }
    }
    out
}

/// Lowercase hex of `bytes`.
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// FNV-1a, for file names.
fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Writes `input` to `dir/<target>/<prefix>-<hash>.bin`.
fn save(dir: &Path, target: &str, prefix: &str, input: &[u8]) -> Result<PathBuf, FuzzError> {
    let dir = dir.join(target);
    std::fs::create_dir_all(&dir).map_err(io(format!("create {}", dir.display())))?;
    let path = dir.join(format!("{prefix}-{:016x}.bin", fnv(input)));
    std::fs::write(&path, input).map_err(io(format!("write {}", path.display())))?;
    Ok(path)
}

thread_local! {
    static LAST_PANIC: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
}

/// Installs (once) a panic hook that records the message of panics on
/// threads that run inputs instead of printing it; other panics print as
/// usual.
fn install_quiet_hook() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let fuzzing = LAST_PANIC.with(|p| {
                let mut p = p.borrow_mut();
                if p.as_deref() == Some("") {
                    *p = Some(format!("{info}").replace('\n', " "));
                    true
                } else {
                    false
                }
            });
            if !fuzzing {
                previous(info);
            }
        }));
    });
}

/// Runs one input on this thread, catching a panic.
fn run_caught(target: &Target, input: &[u8]) -> Result<Outcome, String> {
    install_quiet_hook();
    LAST_PANIC.with(|p| *p.borrow_mut() = Some(String::new()));
    let result = catch_unwind(AssertUnwindSafe(|| (target.run)(input)));
    let message = LAST_PANIC
        .with(|p| p.borrow_mut().take())
        .unwrap_or_default();
    result.map_err(|_| message)
}

fn exec_in_process(target: &Target, input: &[u8], timeout: Duration) -> Exec {
    let t = Instant::now();
    let result = run_caught(target, input);
    let elapsed = t.elapsed();
    match result {
        Err(message) => Exec::Crashed(CrashKind::Panic, message),
        Ok(_) if elapsed > timeout => Exec::Crashed(
            CrashKind::Timeout,
            format!(
                "{:.2} s (bound {:.2} s)",
                elapsed.as_secs_f64(),
                timeout.as_secs_f64()
            ),
        ),
        Ok(outcome) => Exec::Done(outcome),
    }
}

/// A worker child process and the thread reading its answers.
struct Worker {
    child: Child,
    stdin: ChildStdin,
    answers: Receiver<std::io::Result<(u8, String)>>,
}

impl Worker {
    fn start(exe: &Path, target: &str, memory_mb: u64) -> Result<Self, FuzzError> {
        let sh = Path::new("/bin/sh");
        let mut cmd = if memory_mb > 0 && sh.exists() {
            let mut c = Command::new(sh);
            c.arg("-c")
                .arg(format!(
                    "ulimit -v {} && exec \"$0\" \"$@\"",
                    memory_mb * 4 * 1024
                ))
                .arg(exe);
            c
        } else {
            Command::new(exe)
        };
        cmd.arg("--worker")
            .arg(target)
            .arg("--memory-mb")
            .arg(memory_mb.to_string())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit());
        let mut child = cmd
            .spawn()
            .map_err(io(format!("start worker {}", exe.display())))?;
        let stdin = child.stdin.take().expect("piped");
        let mut stdout = child.stdout.take().expect("piped");
        let (tx, answers) = channel();
        std::thread::spawn(move || {
            loop {
                let answer = read_answer(&mut stdout);
                let end = answer.is_err();
                if tx.send(answer).is_err() || end {
                    return;
                }
            }
        });
        Ok(Self {
            child,
            stdin,
            answers,
        })
    }

    fn exec(&mut self, input: &[u8], timeout: Duration) -> Result<Exec, FuzzError> {
        let t = Instant::now();
        let sent = self
            .stdin
            .write_all(&(input.len() as u32).to_le_bytes())
            .and_then(|()| self.stdin.write_all(input))
            .and_then(|()| self.stdin.flush());
        if sent.is_err() {
            return Ok(Exec::Crashed(CrashKind::Died, self.status()));
        }
        match self.answers.recv_timeout(timeout) {
            Ok(Ok((0, _))) => Ok(Exec::Done(Ok(()))),
            Ok(Ok((1, message))) => Ok(Exec::Done(Err(message))),
            Ok(Ok((2, message))) => Ok(Exec::Crashed(CrashKind::Panic, message)),
            Ok(Ok((3, message))) => Ok(Exec::Crashed(CrashKind::Memory, message)),
            Ok(Ok((s, _))) => Err(FuzzError::Protocol(format!("status byte {s}"))),
            Ok(Err(_)) | Err(RecvTimeoutError::Disconnected) => {
                Ok(Exec::Crashed(CrashKind::Died, self.status()))
            }
            Err(RecvTimeoutError::Timeout) => Ok(Exec::Crashed(
                CrashKind::Timeout,
                format!(
                    "no answer after {:.2} s (bound {:.2} s)",
                    t.elapsed().as_secs_f64(),
                    timeout.as_secs_f64()
                ),
            )),
        }
    }

    /// Waits for the (dying) worker and describes how it ended.
    fn status(&mut self) -> String {
        let _ = self.child.kill();
        match self.child.wait() {
            Ok(s) => format!("worker ended: {s}"),
            Err(e) => format!("worker lost: {e}"),
        }
    }

    fn stop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn read_answer(r: &mut impl Read) -> std::io::Result<(u8, String)> {
    let mut head = [0u8; 5];
    r.read_exact(&mut head)?;
    let len = u32::from_le_bytes([head[1], head[2], head[3], head[4]]) as usize;
    let mut msg = vec![0u8; len];
    r.read_exact(&mut msg)?;
    Ok((head[0], String::from_utf8_lossy(&msg).into_owned()))
}

/// Peak resident memory of this process (`VmHWM`, bytes), where `/proc`
/// has it.
fn peak_rss() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// The worker side: reads inputs from stdin, runs `target` on each and
/// answers on stdout, until stdin closes. After an input that took over
/// 5 ms, a peak resident memory above `memory_mb` (0: unchecked) is
/// answered as a memory crash and the worker exits (the parent starts a
/// fresh one).
///
/// # Errors
/// [`FuzzError::Io`] when stdin or stdout fail.
pub fn serve_worker(target: &Target, memory_mb: u64) -> Result<(), FuzzError> {
    let mut stdin = std::io::stdin().lock();
    let mut stdout = std::io::stdout().lock();
    loop {
        let mut len = [0u8; 4];
        match stdin.read_exact(&mut len) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(()),
            Err(e) => return Err(io("worker stdin")(e)),
        }
        let mut input = vec![0u8; u32::from_le_bytes(len) as usize];
        stdin.read_exact(&mut input).map_err(io("worker stdin"))?;
        let t = Instant::now();
        let (mut status, mut message) = match run_caught(target, &input) {
            Ok(Ok(())) => (0u8, String::new()),
            Ok(Err(e)) => (1, e),
            Err(panic) => (2, panic),
        };
        let over = (memory_mb > 0 && t.elapsed() > Duration::from_millis(5))
            .then(peak_rss)
            .flatten()
            .filter(|&peak| peak > memory_mb << 20);
        if let Some(peak) = over {
            status = 3;
            message = format!(
                "peak resident memory {} MiB over the {memory_mb} MiB bound",
                peak >> 20
            );
        }
        // Error texts only feed signatures: the first 4 KiB are enough.
        let mut end = message.len().min(4096);
        while !message.is_char_boundary(end) {
            end -= 1;
        }
        let message = &message.as_bytes()[..end];
        stdout
            .write_all(&[status])
            .and_then(|()| stdout.write_all(&(message.len() as u32).to_le_bytes()))
            .and_then(|()| stdout.write_all(message))
            .and_then(|()| stdout.flush())
            .map_err(io("worker stdout"))?;
        if over.is_some() {
            return Ok(());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn panicky(bytes: &[u8]) -> Outcome {
        if bytes.first() == Some(&b'!') {
            panic!("bang");
        }
        Err(format!("error {} at `{:?}`", bytes.len(), bytes))
    }

    #[test]
    fn in_process_catches_panics_and_counts() {
        let target = Target {
            name: "panicky",
            about: "test",
            run: panicky,
            seeds: || vec![b"!".to_vec(), b"abc".to_vec()],
            dictionary: &[],
            max_len: 16,
        };
        let options = Options {
            duration: Duration::from_millis(200),
            ..Options::default()
        };
        let r = run(&target, &options).unwrap();
        assert!(r.inputs > 10, "{r:?}");
        assert!(r.crashes >= 1);
        assert_eq!(r.crash_list[0].kind, CrashKind::Panic);
        assert!(
            r.crash_list[0].message.contains("bang"),
            "{:?}",
            r.crash_list[0]
        );
        assert_eq!(r.crash_list[0].hex, "21");
    }

    #[test]
    fn shapes_blur_numbers_and_quotes() {
        assert_eq!(shape_of("line 12: bad `x1` at 3"), "line #: bad \"\" at #");
    }
}
