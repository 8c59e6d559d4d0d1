//! `metaplate monitor` over HTTP, as a script or a browser sees it: a finished scan, a scan followed from before its
//! dataset exists to its end (events, reconnection with `Last-Event-ID`), the Host and method guard, and the page in
//! headless Chromium while a scan runs (Debian's `chromium`, installed by `scripts/install-deps.sh`; another binary
//! through `METAPLATE_CHROMIUM`).

// Helpers outside #[test] functions unwrap too: a failure there is a failed test.
#![allow(clippy::unwrap_used)]

use std::collections::HashSet;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use browser::{colours, headless, screenshot};
use serde_json::Value;

use crate::browser;

/// The scan of `recipes.rs` (3 x 2 points of the metamaterial plate, the quick protocol, the scene's own seed), so that
/// the files share one Green's-function cache entry.
const SCAN: &[&str] = &["--scene", "metamaterial", "--protocol", "quick", "--grid", "3x2"];

fn cache_dir() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache")
}

/// `metaplate scan` into `out` (resuming with `resume`), started (not waited for), each commit made to last
/// `commit_pause_ms` longer (the store's test hook) so that a person (or a test) can watch a run of a few seconds.
fn start_scan(out: &Path, resume: bool, commit_pause_ms: u64) -> Child {
    let cache = cache_dir();
    Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(["scan", "--uncalibrated", "--out", out.to_str().unwrap(), "--cache-dir", cache.to_str().unwrap()])
        .args(SCAN)
        .args(resume.then_some("--resume"))
        .env("METAPLATE_TEST_COMMIT_PAUSE_MS", commit_pause_ms.to_string())
        .env("RUST_BACKTRACE", "0")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

fn wait_ok(child: Child) {
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "scan failed: {}", String::from_utf8_lossy(&out.stderr));
}

/// A monitor process on a free loopback port, killed when dropped.
struct Monitor {
    child: Child,
    port: u16,
}

impl Monitor {
    fn start(dir: &Path) -> Self {
        Self::start_with(dir, &[])
    }

    fn start_with(dir: &Path, extra: &[&str]) -> Self {
        Self::start_env(dir, extra, &[])
    }

    fn start_env(dir: &Path, extra: &[&str], env: &[(&str, &str)]) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_metaplate"))
            .args(["monitor", dir.to_str().unwrap(), "--bind", "127.0.0.1:0"])
            .args(extra)
            .envs(env.iter().copied())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .unwrap();
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
        // "monitor: http://127.0.0.1:PORT/ following ..."
        let port = line.split("127.0.0.1:").nth(1).and_then(|r| r.split('/').next()).map(|p| p.parse().unwrap());
        Self { port: port.unwrap_or_else(|| panic!("no address in {line:?}")), child }
    }

    /// One request with `Host: 127.0.0.1:PORT` unless `host` says otherwise; returns the status and the body.
    fn request(&self, method: &str, path: &str, host: Option<&str>) -> (u16, String) {
        let host = host.map_or_else(|| format!("127.0.0.1:{}", self.port), str::to_owned);
        let mut stream = TcpStream::connect(("127.0.0.1", self.port)).unwrap();
        write!(stream, "{method} {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\nContent-Length: 0\r\n\r\n")
            .unwrap();
        let mut response = String::new();
        stream.read_to_string(&mut response).unwrap();
        let status = response.split(' ').nth(1).and_then(|s| s.parse().ok()).unwrap_or(0);
        let body = response.split_once("\r\n\r\n").map_or("", |(_, b)| b).to_owned();
        (status, body)
    }

    fn get_json(&self, path: &str) -> Value {
        let (status, body) = self.request("GET", path, None);
        assert_eq!(status, 200, "{path}: {body}");
        serde_json::from_str(&body).unwrap()
    }

    /// Opens `/events` (with `Last-Event-ID` if given).
    fn events(&self, last_event_id: Option<u64>) -> Events {
        let mut stream = TcpStream::connect(("127.0.0.1", self.port)).unwrap();
        let resume = last_event_id.map_or_else(String::new, |id| format!("Last-Event-ID: {id}\r\n"));
        write!(
            stream,
            "GET /events HTTP/1.1\r\nHost: localhost:{}\r\nAccept: text/event-stream\r\n{resume}\r\n",
            self.port
        )
        .unwrap();
        stream.set_read_timeout(Some(Duration::from_millis(200))).unwrap();
        Events { reader: BufReader::new(stream), id: None, event: None }
    }

    /// Polls `/api/state` until `done` says yes (at most 120 s: the first run may fill the cache).
    fn wait_state(&self, done: impl Fn(&Value) -> bool) -> Value {
        let start = Instant::now();
        loop {
            let state = self.get_json("/api/state");
            if done(&state) {
                return state;
            }
            assert!(start.elapsed() < Duration::from_secs(120), "timed out; last state {state}");
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Monitor {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A server-sent event stream, read line by line (chunked transfer framing lines are skipped: they are not fields).
struct Events {
    reader: BufReader<TcpStream>,
    id: Option<u64>,
    event: Option<String>,
}

/// One `commit` event: its id, its data and when it arrived.
struct Commit {
    id: u64,
    data: Value,
    arrived: chrono::DateTime<chrono::Utc>,
}

impl Events {
    /// The next `commit` event, or `None` if none comes within `timeout`.
    fn next_commit(&mut self, timeout: Duration) -> Option<Commit> {
        let start = Instant::now();
        let mut line = String::new();
        while start.elapsed() < timeout {
            line.clear();
            match self.reader.read_line(&mut line) {
                Ok(0) => return None,
                Ok(_) => {}
                Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {
                    continue;
                }
                Err(e) => panic!("{e}"),
            }
            let line = line.trim_end();
            if let Some(id) = line.strip_prefix("id: ") {
                self.id = id.parse().ok();
            } else if let Some(event) = line.strip_prefix("event: ") {
                self.event = Some(event.to_owned());
            } else if let Some(data) = line.strip_prefix("data: ")
                && self.event.as_deref() == Some("commit")
            {
                let data = serde_json::from_str(data).unwrap();
                let id = self.id.take().unwrap();
                return Some(Commit { id, data, arrived: chrono::Utc::now() });
            }
        }
        None
    }
}

#[test]
fn a_finished_scan_is_served_read_only_and_to_loopback_names_only() {
    let tmp = tempfile::tempdir().unwrap();
    let scan = tmp.path().join("scan");
    wait_ok(start_scan(&scan, false, 0));
    let monitor = Monitor::start(&scan);

    let state = monitor.get_json("/api/state");
    assert_eq!(state["status"], "finished", "{state}");
    assert_eq!((state["points_total"].as_u64(), state["points_done"].as_u64()), (Some(6), Some(6)), "{state}");
    assert_eq!(state["status_counts"]["pending"], 0, "{state}");
    let counted: u64 = state["status_counts"].as_object().unwrap().values().filter_map(Value::as_u64).sum();
    assert_eq!(counted, 6, "{state}");
    assert_eq!(state["remaining_s"]["median"].as_f64(), Some(0.0), "{state}");
    assert!(state["elapsed_s"].as_f64().unwrap() > 0.0 && state["last_commit_age_s"].as_f64().is_some(), "{state}");
    assert!(state["disk"]["free_bytes"].as_u64().unwrap() > 0, "{state}");
    assert_eq!(state["stalled"], false);

    // One point: every actuator's row, with its response.
    let manifest: Value = serde_json::from_str(&std::fs::read_to_string(scan.join("manifest.json")).unwrap()).unwrap();
    let point = manifest["config"]["points"][0].as_u64().unwrap();
    let one = monitor.get_json(&format!("/api/point/{point}"));
    assert_eq!(one["point"].as_u64(), Some(point));
    let rows = one["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 8, "{}", one["status"]);
    assert!(rows.iter().all(|r| r["ir"].as_array().is_some_and(|ir| ir.len() == 12_000)));
    assert_eq!(monitor.request("GET", "/api/point/0", None).0, 404, "a point not measured");

    // The page: self-contained (nothing fetched but its own API).
    let (status, page) = monitor.request("GET", "/", None);
    assert_eq!(status, 200);
    for outside in
        ["<script src", "<link", "@import", "url(", "src=\"http", "href=\"http", "(\"http", "('http", "//fonts"]
    {
        assert!(!page.contains(outside), "the page fetches something from outside ({outside})");
    }
    assert_eq!(monitor.request("HEAD", "/", None).0, 200);

    // Nothing changes anything; only loopback names are served (DNS rebinding).
    for method in ["POST", "PUT", "DELETE", "PATCH"] {
        assert_eq!(monitor.request(method, "/api/state", None).0, 405, "{method}");
    }
    assert_eq!(monitor.request("POST", "/no/such/page", None).0, 405);
    for host in ["evil.example", "evil.example:80", "127.0.0.1.evil.example", "10.0.0.1", "[::2]:80"] {
        assert_eq!(monitor.request("GET", "/api/state", Some(host)).0, 403, "{host}");
    }
    for host in ["localhost", "LOCALHOST:8765", "127.0.0.1", "[::1]:1234", "monitor.localhost"] {
        assert_eq!(monitor.request("GET", "/api/state", Some(host)).0, 200, "{host}");
    }

    // A reconnecting client gets what it missed, in order.
    let mut events = monitor.events(Some(2));
    let ids: Vec<u64> =
        std::iter::from_fn(|| events.next_commit(Duration::from_secs(5)).map(|c| c.id)).take(3).collect();
    assert_eq!(ids, [3, 4, 5]);
}

#[test]
fn a_scan_is_followed_from_before_its_dataset_exists_to_its_end_with_an_event_per_commit() {
    let tmp = tempfile::tempdir().unwrap();
    let scan = tmp.path().join("scan");
    let monitor = Monitor::start(&scan);
    assert_eq!(monitor.get_json("/api/state")["status"], "waiting");
    let mut events = monitor.events(None);
    let run = start_scan(&scan, false, 0);

    let first = events.next_commit(Duration::from_secs(120)).expect("a commit event");
    assert_eq!((first.id, &first.data["seq"]), (0, &Value::from(0)));
    let mut latencies_s = Vec::new();
    let mut ids = vec![first.id];
    let mut seen = vec![first];
    // Disconnect after the third commit and come back with the last id seen: nothing is lost or repeated.
    while ids.len() < 3 {
        let commit = events.next_commit(Duration::from_secs(30)).expect("a commit event");
        ids.push(commit.id);
        seen.push(commit);
    }
    drop(events);
    let mut events = monitor.events(Some(*ids.last().unwrap()));
    while let Some(commit) = events.next_commit(Duration::from_secs(30)) {
        ids.push(commit.id);
        seen.push(commit);
        if ids.len() == 6 {
            break;
        }
    }
    assert_eq!(ids, [0, 1, 2, 3, 4, 5]);
    wait_ok(run);
    for commit in &seen[..3] {
        let at = chrono::DateTime::parse_from_rfc3339(commit.data["at"].as_str().unwrap()).unwrap();
        latencies_s.push((commit.arrived - at.with_timezone(&chrono::Utc)).as_seconds_f64());
    }
    // Live events (the ones before the reconnection) arrive within a second of the commit.
    assert!(latencies_s.iter().all(|l| *l < 1.0), "latencies {latencies_s:?} s");
    let points: HashSet<u64> = seen.iter().filter_map(|c| c.data["point"].as_u64()).collect();
    assert_eq!(points.len(), 6);
    assert!(seen.iter().all(|c| c.data["status"].is_string()), "every commit carries its point's status");

    let state = monitor.wait_state(|s| s["status"] == "finished");
    assert_eq!(state["points_done"].as_u64(), Some(6));
    assert!(state["median_point_s"].as_f64().unwrap() > 0.0, "{state}");
}

#[test]
fn a_killed_scan_shows_where_it_stopped_and_its_resume_is_followed_to_the_end() {
    let tmp = tempfile::tempdir().unwrap();
    let scan = tmp.path().join("scan");
    let monitor = Monitor::start(&scan);
    let mut run = start_scan(&scan, false, 300);
    monitor.wait_state(|s| s["points_done"].as_u64().is_some_and(|n| n >= 2));
    run.kill().unwrap();
    run.wait().unwrap();
    std::thread::sleep(5 * metaplate_monitor::POLL_INTERVAL);
    let killed = monitor.get_json("/api/state");
    let done = killed["points_done"].as_u64().unwrap();
    assert!((2..6).contains(&done), "{killed}");
    assert_eq!(killed["status_counts"]["pending"].as_u64(), Some(6 - done), "{killed}");
    assert!(killed["status"] == "running" || killed["status"] == "stalled", "{killed}");
    assert!(killed["remaining_s"]["p90"].as_f64().unwrap() >= killed["remaining_s"]["median"].as_f64().unwrap());
    assert!(killed["finish_at"]["median"].is_string(), "{killed}");

    wait_ok(start_scan(&scan, true, 0));
    let state = monitor.wait_state(|s| s["status"] == "finished");
    assert_eq!(state["points_done"].as_u64(), Some(6), "{state}");
}

#[test]
fn a_run_deleted_and_started_again_in_its_directory_is_followed_from_its_first_commit() {
    let tmp = tempfile::tempdir().unwrap();
    let scan = tmp.path().join("scan");
    wait_ok(start_scan(&scan, false, 0));
    let monitor = Monitor::start(&scan);
    let mut events = monitor.events(None);
    std::fs::remove_dir_all(&scan).unwrap();
    monitor.wait_state(|s| s["status"] == "waiting");
    wait_ok(start_scan(&scan, false, 0));
    let ids: Vec<u64> =
        std::iter::from_fn(|| events.next_commit(Duration::from_secs(30)).map(|c| c.id)).take(6).collect();
    assert_eq!(ids, [0, 1, 2, 3, 4, 5], "the new run's commits, from its first");
    assert_eq!(monitor.wait_state(|s| s["status"] == "finished")["points_done"].as_u64(), Some(6));
}

#[test]
fn a_calibration_is_followed_actuator_by_actuator() {
    let tmp = tempfile::tempdir().unwrap();
    let cal = tmp.path().join("cal");
    let cache = cache_dir();
    let out = Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(["calibrate", "--scene", "metamaterial", "--out", cal.to_str().unwrap()])
        .args(["--cache-dir", cache.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let monitor = Monitor::start(&cal);
    let state = monitor.get_json("/api/state");
    assert_eq!((state["unit"].as_str(), state["status"].as_str()), (Some("actuator"), Some("finished")), "{state}");
    assert_eq!((state["points_total"].as_u64(), state["points_done"].as_u64()), (Some(8), Some(8)), "{state}");
    let view = monitor.get_json("/api/view");
    assert!(view["status_svg"].is_null(), "a calibration has no grid to draw");
    let kinds: Vec<&str> =
        view["spectrum"]["actuators"].as_array().unwrap().iter().filter_map(|a| a["kind"].as_str()).collect();
    assert_eq!(kinds.len(), 3, "the last actuator's filter, response and verification: {kinds:?}");
    let last = monitor.events(Some(6)).next_commit(Duration::from_secs(5)).unwrap();
    assert_eq!((last.id, last.data["actuator"].as_u64()), (7, Some(7)), "{}", last.data);
}

#[test]
fn the_page_renders_the_grid_the_snr_map_and_the_spectra_in_chromium_while_a_scan_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let scan = tmp.path().join("scan");
    let monitor = Monitor::start(&scan);
    let run = start_scan(&scan, false, 300);
    // The page is opened once the first point is in, while the run goes on.
    monitor.wait_state(|s| s["points_done"].as_u64().is_some_and(|n| n >= 1));
    let png = tmp.path().join("monitor.png");
    let (info, pixels) = screenshot(&format!("http://localhost:{}/", monitor.port), &png, 1400, 1000);
    wait_ok(run);
    let colours = colours(&info, &pixels);
    // The status map's measured green, the spectrum's first two actuators' colours, and SNR cells (viridis, not in
    // the colour bar's few steps alone: any of its yellows and greens) are drawn.
    for (what, rgb) in
        [("measured cells", [0x00, 0x9e, 0x73]), ("spectrum", [0x00, 0x72, 0xb2]), ("spectrum", [0xd5, 0x5e, 0x00])]
    {
        assert!(colours.contains(&rgb), "no {what} ({rgb:02x?}) in the screenshot");
    }
    // What the page shows as text, after its script ran: progress and a remaining time or the end.
    let profile = tempfile::tempdir().unwrap();
    let dom =
        headless(profile.path()).args(["--dump-dom", &format!("http://localhost:{}/", monitor.port)]).output().unwrap();
    let dom = String::from_utf8_lossy(&dom.stdout);
    assert!(dom.contains("6 / 6 points"), "the page shows the progress: {dom}");
    assert!(dom.contains("<svg") && dom.contains("act 7"), "maps and spectra: {dom}");
    // The run has finished: the page says so, and when, instead of the time since the last commit and a stall
    // warning.
    let agebox = dom.split(r#"id="agebox""#).nth(1).and_then(|box_| box_.split("</div></div>").next()).unwrap();
    assert!(agebox.contains(r#"id="agekey">finished<"#) && agebox.ends_with(" ago"), "{agebox}");
    assert!(!agebox.contains("since the last commit") && !agebox.to_lowercase().contains("stall warning"), "{agebox}");
}

#[test]
fn a_file_given_as_the_run_directory_is_refused_at_once_by_name() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("scan.log");
    std::fs::write(&file, "not a run directory").unwrap();
    let started = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(["monitor", file.to_str().unwrap(), "--bind", "127.0.0.1:0"])
        .env("RUST_BACKTRACE", "0")
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(started.elapsed() < Duration::from_secs(10), "refused at once, not waited for: {:?}", started.elapsed());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains(&format!("{} is a file, not a run directory", file.display())), "{stderr}");
    assert!(out.stdout.is_empty(), "nothing served");
}

#[test]
fn the_monitor_notifies_the_end_of_a_run_it_watched_once() {
    let tmp = tempfile::tempdir().unwrap();
    let (dir, notes) = (tmp.path().join("scan"), tmp.path().join("notes.jsonl"));
    let notify = format!("cat >> '{}'", notes.display());
    let _monitor = Monitor::start_with(&dir, &["--notify-command", &notify]);
    wait_ok(start_scan(&dir, false, 100));
    let read = || std::fs::read_to_string(&notes).unwrap_or_default();
    let deadline = Instant::now() + Duration::from_secs(20);
    while !read().contains("\"finished\"") && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(100));
    }
    // A few more polls: the finish is not notified again.
    std::thread::sleep(Duration::from_millis(2500));
    let got: Vec<Value> = read().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let finished: Vec<&Value> = got.iter().filter(|n| n["event"] == "finished").collect();
    assert_eq!(finished.len(), 1, "{got:?}");
    assert_eq!((finished[0]["done"].as_u64(), finished[0]["total"].as_u64()), (Some(6), Some(6)), "{got:?}");
    assert_eq!(finished[0]["source"], "monitor");
}

#[test]
fn a_slow_disk_delays_the_news_not_the_answers() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("scan");
    wait_ok(start_scan(&dir, false, 0));
    // Every poll of the run's files takes 2 s, as on a slow network disk; requests must not wait for one.
    let monitor = Monitor::start_env(&dir, &[], &[("METAPLATE_TEST_POLL_PAUSE_MS", "2000")]);
    let started = Instant::now();
    for path in ["/api/state", "/api/view", "/", "/api/state", "/api/view"] {
        let (status, body) = monitor.request("GET", path, None);
        assert_eq!(status, 200, "{path}: {body}");
    }
    // Five answers in less time than one poll: none of them waited for the disk.
    assert!(started.elapsed() < Duration::from_millis(2000), "{:?}", started.elapsed());
    let (_, body) = monitor.request("GET", "/api/state", None);
    let state: Value = serde_json::from_str(&body).unwrap();
    assert_eq!(state["points_done"], 6, "{state}");
}
