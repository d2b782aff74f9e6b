//! The steps of `billow view` (reading the assets, the adapter, uploads, pipelines,
//! frames): each timed (`--json`'s `startup_ms`), and named on stderr when it takes longer
//! than a second (not with `--quiet`), one line per slow step: its name once it has run a
//! second, its time when it ends — `view: rendering the first frame… 12.3 s`. A step that
//! ends within the second prints nothing. The renderer prints nothing itself: it reports
//! its steps to a callback (`Content::build_with`).

use std::io::Write;
use std::sync::mpsc::{channel, RecvTimeoutError, Sender};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long a step runs before it is named.
pub const ANNOUNCE_AFTER: Duration = Duration::from_secs(1);

enum Msg {
    Start(String),
    End(Duration),
}

/// Times steps and names the slow ones on a sink (a watcher thread waits for a step to
/// pass [`ANNOUNCE_AFTER`]).
pub struct Steps {
    tx: Option<Sender<Msg>>,
    watcher: Option<JoinHandle<()>>,
    started: Option<Instant>,
}

impl Steps {
    /// Steps named on stderr after [`ANNOUNCE_AFTER`], or (`quiet`) only timed.
    pub fn stderr(quiet: bool) -> Steps {
        if quiet {
            Steps::silent()
        } else {
            Steps::new(Box::new(std::io::stderr()), ANNOUNCE_AFTER)
        }
    }

    /// Steps only timed.
    pub fn silent() -> Steps {
        Steps {
            tx: None,
            watcher: None,
            started: None,
        }
    }

    /// Steps named on `sink` once one has run for `after`.
    pub fn new(mut sink: Box<dyn Write + Send>, after: Duration) -> Steps {
        let (tx, rx) = channel::<Msg>();
        let watcher = std::thread::spawn(move || {
            // The step running: (its name, when it started, whether it was named).
            let mut current: Option<(String, Instant, bool)> = None;
            loop {
                let msg = match &current {
                    Some((_, t0, false)) => rx.recv_timeout(after.saturating_sub(t0.elapsed())),
                    _ => rx.recv().map_err(|_| RecvTimeoutError::Disconnected),
                };
                // Write errors (a closed stderr) are ignored: the steps are only news.
                match msg {
                    Ok(Msg::Start(what)) => current = Some((what, Instant::now(), false)),
                    Ok(Msg::End(d)) => {
                        if let Some((_, _, true)) = current {
                            let _ = writeln!(sink, " {}", seconds(d));
                        }
                        current = None;
                    }
                    Err(RecvTimeoutError::Timeout) => {
                        if let Some((what, _, named)) = &mut current {
                            let _ = write!(sink, "view: {what}…");
                            let _ = sink.flush();
                            *named = true;
                        }
                    }
                    Err(RecvTimeoutError::Disconnected) => {
                        if let Some((_, _, true)) = current {
                            let _ = writeln!(sink);
                        }
                        return;
                    }
                }
            }
        });
        Steps {
            tx: Some(tx),
            watcher: Some(watcher),
            started: None,
        }
    }

    /// A step begins (ending the one before, if any).
    pub fn start(&mut self, what: impl Into<String>) {
        self.end();
        self.started = Some(Instant::now());
        if let Some(tx) = &self.tx {
            let _ = tx.send(Msg::Start(what.into()));
        }
    }

    /// The step running ends; returns its time (zero when none ran).
    pub fn end(&mut self) -> Duration {
        let Some(t0) = self.started.take() else {
            return Duration::ZERO;
        };
        let d = t0.elapsed();
        if let Some(tx) = &self.tx {
            let _ = tx.send(Msg::End(d));
        }
        d
    }

    /// Runs `f` as the step `what`; returns its value and time.
    pub fn run<T>(&mut self, what: impl Into<String>, f: impl FnOnce() -> T) -> (T, Duration) {
        self.start(what);
        let v = f();
        (v, self.end())
    }
}

impl Drop for Steps {
    fn drop(&mut self) {
        self.end();
        self.tx = None;
        if let Some(w) = self.watcher.take() {
            let _ = w.join();
        }
    }
}

fn seconds(d: Duration) -> String {
    format!("{:.1} s", d.as_secs_f64())
}

/// Milliseconds of `d`, for `--json`.
pub fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::{Arc, Mutex};

    #[derive(Clone, Default)]
    struct Shared(Arc<Mutex<Vec<u8>>>);

    impl Write for Shared {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            self.0.lock().unwrap().extend_from_slice(b);
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    fn text(s: &Shared) -> String {
        String::from_utf8(s.0.lock().unwrap().clone()).unwrap()
    }

    #[test]
    fn slow_steps_are_named_with_their_time_on_one_line() {
        let out = Shared::default();
        let mut steps = Steps::new(Box::new(out.clone()), Duration::from_millis(20));
        let (v, d) = steps.run("building the pipelines", || {
            std::thread::sleep(Duration::from_millis(200));
            7
        });
        assert_eq!(v, 7);
        assert!(d >= Duration::from_millis(200));
        drop(steps);
        assert_eq!(text(&out), "view: building the pipelines… 0.2 s\n");
    }

    #[test]
    fn quick_steps_print_nothing_and_are_still_timed() {
        let out = Shared::default();
        let mut steps = Steps::new(Box::new(out.clone()), Duration::from_secs(3600));
        steps.start("uploading the content");
        std::thread::sleep(Duration::from_millis(5));
        let d = steps.end();
        assert!(d >= Duration::from_millis(5));
        assert_eq!(steps.end(), Duration::ZERO, "nothing runs any more");
        drop(steps);
        assert_eq!(text(&out), "");
        let mut quiet = Steps::silent();
        let ((), d) = quiet.run("x", || std::thread::sleep(Duration::from_millis(2)));
        assert!(d >= Duration::from_millis(2));
    }

    #[test]
    fn a_step_cut_short_still_ends_its_line() {
        let out = Shared::default();
        let mut steps = Steps::new(Box::new(out.clone()), Duration::from_millis(10));
        steps.start("rendering the first frame");
        std::thread::sleep(Duration::from_millis(100));
        steps.start("rendering frame 2 of 2");
        std::thread::sleep(Duration::from_millis(100));
        drop(steps);
        let t = text(&out);
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(lines.len(), 2, "{t:?}");
        assert!(
            lines[0].starts_with("view: rendering the first frame… 0."),
            "{t:?}"
        );
        assert!(
            lines[1].starts_with("view: rendering frame 2 of 2… 0."),
            "{t:?}"
        );
        assert!(t.ends_with(" s\n"), "{t:?}");
    }
}
