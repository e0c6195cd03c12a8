//! A second, differently built judge: FLIP (Andersson et al., "FLIP: A
//! Difference Evaluator for Alternating Images", HPG 2020), NVIDIA's
//! `flip-evaluator` Python package run in a child process
//! (`bench/flip/flip_judge.py`; `bench/flip/setup.sh` installs it). A
//! still-image metric with its own contrast sensitivity per pixels per degree:
//! each judged frame is compared alone and the mean of the per-frame mean FLIP
//! errors reported (0: no difference; lower is better). The frames are those the
//! ColorVideoVDP judge sees (`jod::shown`), grey as three equal sRGB channels.

use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::Mutex;

use crate::eval::jod::shown;
use fsot::error::{Error, Result};

/// The helper's source, run with `python -c`.
const SCRIPT: &str = include_str!("../../../../bench/flip/flip_judge.py");

struct Pipe {
    child: Child,
    input: ChildStdin,
    output: BufReader<ChildStdout>,
}

/// FLIP in a Python child process.
pub struct Flip {
    pipe: Mutex<Pipe>,
    pub python: String,
}

impl Flip {
    /// Starts the helper with `python` (one with flip-evaluator and numpy installed).
    pub fn start(python: &Path) -> Result<Self> {
        let mut child = Command::new(python)
            .args(["-c", SCRIPT])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .map_err(|e| Error::io(format!("cannot start FLIP's helper with {}", python.display()), e))?;
        let (input, output) = match (child.stdin.take(), child.stdout.take()) {
            (Some(i), Some(o)) => (i, BufReader::new(o)),
            _ => return Err(Error::invalid("FLIP's helper has no pipes")),
        };
        let flip =
            Self { pipe: Mutex::new(Pipe { child, input, output }), python: python.display().to_string() };
        // A one-frame sequence proves the package is there before the long work.
        let frame = vec![vec![0.5; 4 * 4]];
        flip.judge(&frame, &frame, 0, 4, 60.0).map_err(|e| {
            Error::invalid(format!(
                "FLIP does not run with {} ({e}); bench/flip/setup.sh installs it",
                python.display()
            ))
        })?;
        Ok(flip)
    }

    /// The mean FLIP error of `render` against `reference` (n x n frames, from
    /// `start`) seen at `ppd` pixels per degree.
    pub fn judge(
        &self,
        render: &[Vec<f64>],
        reference: &[Vec<f64>],
        start: usize,
        n: usize,
        ppd: f64,
    ) -> Result<f64> {
        let [test, refs] = shown(render, reference, start);
        let mut bytes = Vec::with_capacity(8 * n * n * test.len() + 64);
        bytes.extend(format!("{n} {n} {} {ppd}\n", test.len()).as_bytes());
        for v in test.iter().chain(&refs).flatten() {
            bytes.extend(v.to_le_bytes());
        }
        let mut pipe = self.pipe.lock().map_err(|_| Error::invalid("FLIP's helper: a poisoned lock"))?;
        let broken = |e: std::io::Error| Error::io("FLIP's helper stopped".to_string(), e);
        pipe.input.write_all(&bytes).map_err(broken)?;
        pipe.input.flush().map_err(broken)?;
        let mut line = String::new();
        pipe.output.read_line(&mut line).map_err(broken)?;
        line.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v >= 0.0)
            .ok_or_else(|| Error::invalid(format!("FLIP's helper answered {line:?}")))
    }
}

impl Drop for Flip {
    fn drop(&mut self) {
        if let Ok(mut pipe) = self.pipe.lock() {
            let _ = pipe.child.kill();
            let _ = pipe.child.wait();
        }
    }
}
