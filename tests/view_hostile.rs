//! `coherent view` against hostile and broken input: its server with clients that are
//! slow to ask or never take their answer, a results file that becomes a pipe or is
//! not there yet; a long transcript, one cut short, two of different tasks, two of one
//! name in two folders, and a folder name that would drive the terminal.

mod common;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use common::{coherent, demo, embedded, env0, scratch, show, utf8};
use serde_json::Value;

/// `coherent run` on the demo (the built-in backend unless `extra` says otherwise) into
/// `dir`: its transcript.
fn run_demo(dir: &Path, extra: &[&str]) -> PathBuf {
    let demo = demo();
    let mut args = vec!["run", utf8(&demo), "--out", utf8(dir)];
    args.extend(extra);
    let out = coherent(&args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let path = stdout
        .lines()
        .find_map(|l| l.strip_prefix("transcript: "))
        .unwrap_or_else(|| panic!("no transcript line\n{}", show(&out)));
    PathBuf::from(path)
}

/// `coherent bench` of the demo with PEFA into `dir/results.jsonl`: its one line.
fn bench_demo(dir: &Path) -> (PathBuf, Value) {
    let results = dir.join("results.jsonl");
    let demo = demo();
    let args = [
        "bench",
        "--tasks",
        utf8(&demo),
        "--methods",
        "pefa",
        "--out",
        utf8(&results),
    ];
    let out = coherent(&args);
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    let text = std::fs::read_to_string(&results).expect("the results file");
    let line = serde_json::from_str(text.trim()).expect("one line");
    (results, line)
}

/// `coherent view --serve path`, and the port it serves on.
struct Served {
    child: Child,
    port: u16,
}

impl Served {
    fn start(path: &Path) -> Served {
        let mut child = Command::new(env!("CARGO_BIN_EXE_coherent"))
            .args(["view", "--serve", utf8(path)])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("the server starts");
        let mut first = String::new();
        let stdout = child.stdout.take().expect("its stdout");
        BufReader::new(stdout)
            .read_line(&mut first)
            .expect("its first line");
        let port = first
            .split("http://127.0.0.1:")
            .nth(1)
            .and_then(|rest| rest.split('/').next())
            .and_then(|p| p.parse().ok())
            .unwrap_or_else(|| panic!("no address in {first:?}"));
        Served { child, port }
    }

    /// `GET target`: the status and the body, or why not within `limit`.
    fn get(&self, target: &str, limit: Duration) -> Result<(u16, String), String> {
        let mut stream = TcpStream::connect(("127.0.0.1", self.port)).map_err(|e| e.to_string())?;
        stream
            .set_read_timeout(Some(limit))
            .map_err(|e| e.to_string())?;
        let head = format!(
            "GET {target} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\n\r\n",
            self.port
        );
        stream
            .write_all(head.as_bytes())
            .map_err(|e| e.to_string())?;
        let mut reply = Vec::new();
        stream
            .read_to_end(&mut reply)
            .map_err(|e| format!("{target}: no whole reply within {limit:?}: {e}"))?;
        let reply = String::from_utf8_lossy(&reply).into_owned();
        let status = reply
            .split(' ')
            .nth(1)
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| format!("{target}: not HTTP: {reply:.200}"))?;
        let body = reply
            .split_once("\r\n\r\n")
            .map_or("", |(_, b)| b)
            .to_owned();
        Ok((status, body))
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A results file whose index is about 12 MB, far more than a connection's buffers
/// hold, in `dir`.
fn big_results(dir: &Path) -> PathBuf {
    let (_, line) = bench_demo(dir);
    let mut text = String::new();
    for seed in 0..200 {
        let mut fat = line.clone();
        fat["seed"] = seed.into();
        fat["error"] = "x".repeat(60_000).into();
        text.push_str(&format!("{fat}\n"));
    }
    let big = dir.join("big.jsonl");
    std::fs::write(&big, text).expect("written");
    big
}

/// Four clients that send their request head a byte at a time, two bytes a second,
/// until `stop`: each one's thread ends when the server cuts the connection, with when.
fn trickling(port: u16, stop: &Arc<AtomicBool>) -> Vec<JoinHandle<Option<Instant>>> {
    (0..4)
        .map(|_| {
            let stop = Arc::clone(stop);
            std::thread::spawn(move || {
                let mut s = TcpStream::connect(("127.0.0.1", port)).ok()?;
                let head = format!("GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n");
                for b in head.bytes().cycle().take(200) {
                    if stop.load(Ordering::Relaxed) || s.write_all(&[b]).is_err() {
                        break;
                    }
                    std::thread::sleep(Duration::from_millis(500));
                }
                let mut rest = Vec::new();
                let _ = s.read_to_end(&mut rest);
                Some(Instant::now())
            })
        })
        .collect()
}

/// Four clients that ask for the index and never read it.
fn silent(port: u16) -> Vec<TcpStream> {
    (0..4)
        .map(|_| {
            let mut s = TcpStream::connect(("127.0.0.1", port)).expect("connects");
            let head = format!("GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n");
            s.write_all(head.as_bytes()).expect("asks");
            s
        })
        .collect()
}

/// `/version` asked of `served` now: answered, and how soon.
fn version_now(served: &Served) -> Duration {
    let asked = Instant::now();
    let (status, body) = served
        .get("/version", Duration::from_secs(5))
        .expect("answered");
    assert_eq!(status, 200);
    assert!(body.trim().parse::<u64>().is_ok(), "{body}");
    asked.elapsed()
}

#[test]
fn clients_slow_to_send_their_request_hold_up_no_one_and_are_cut_off_after_5_s() {
    let dir = scratch("view-serve-slow");
    let served = Served::start(&big_results(&dir));
    let stop = Arc::new(AtomicBool::new(false));
    let started = Instant::now();
    let slow = trickling(served.port, &stop);
    std::thread::sleep(Duration::from_secs(2));
    let answered = version_now(&served);
    assert!(answered < Duration::from_secs(1), "{answered:?}");
    // Each slow client cut off once its head's time (5 s) is up.
    for t in slow {
        let cut = t.join().expect("the thread ends").expect("connected");
        assert!(
            cut - started < Duration::from_secs(8),
            "{:?}",
            cut - started
        );
    }
    stop.store(true, Ordering::Relaxed);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn clients_that_never_read_their_answer_hold_up_no_one_and_are_cut_off_after_10_s() {
    let dir = scratch("view-serve-silent");
    let served = Served::start(&big_results(&dir));
    let started = Instant::now();
    let quiet = silent(served.port);
    // Their indexes made, the server is stuck writing to them, if it is to be stuck.
    std::thread::sleep(Duration::from_secs(3));
    let answered = version_now(&served);
    assert!(answered < Duration::from_secs(1), "{answered:?}");
    let (status, index) = served.get("/", Duration::from_secs(20)).expect("the index");
    assert_eq!(status, 200);
    // Each cut off once its reply's time (10 s from its first byte) is up: what it got
    // ends short of the index. (Its index took a few seconds to make, more on a busy
    // machine, before that time began.)
    std::thread::sleep(Duration::from_secs(25).saturating_sub(started.elapsed()));
    for mut s in quiet {
        s.set_read_timeout(Some(Duration::from_secs(5)))
            .expect("a read time limit");
        let mut got = Vec::new();
        let _ = s.read_to_end(&mut got);
        assert!(got.len() < index.len(), "{} bytes", got.len());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn beside_four_slow_and_four_silent_clients_a_request_is_answered_within_a_second() {
    let dir = scratch("view-serve-stalled");
    let served = Served::start(&big_results(&dir));
    let stop = Arc::new(AtomicBool::new(false));
    let slow = trickling(served.port, &stop);
    let _quiet = silent(served.port);
    std::thread::sleep(Duration::from_secs(3));
    let answered = version_now(&served);
    eprintln!("/version answered in {answered:?} beside 8 hostile clients");
    assert!(answered < Duration::from_secs(1), "{answered:?}");
    // The index itself, made and sent whole.
    let asked = Instant::now();
    let (status, index) = served.get("/", Duration::from_secs(20)).expect("the index");
    eprintln!(
        "/ ({} bytes) answered in {:?}",
        index.len(),
        asked.elapsed()
    );
    assert_eq!(status, 200);
    stop.store(true, Ordering::Relaxed);
    for t in slow {
        let _ = t.join();
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_server_serves_a_results_file_made_in_its_folder_after_it_started() {
    let dir = scratch("view-serve-later");
    let (results, _) = bench_demo(&dir);
    // A folder that does not exist yet.
    let later = dir.join("later");
    let served = Served::start(&later);
    let limit = Duration::from_secs(5);
    let (status, version) = served.get("/version", limit).expect("answered");
    assert_eq!((status, version.trim()), (200, "0"));
    let (status, _) = served.get("/", limit).expect("answered");
    assert_eq!(status, 200);
    // A benchmark writes its results file there.
    std::fs::create_dir(&later).expect("made");
    std::fs::copy(&results, later.join("res.jsonl")).expect("copied");
    let (status, data) = served.get("/results.json", limit).expect("answered");
    assert_eq!(status, 200, "{data}");
    let data: Value = serde_json::from_str(&data).expect("JSON");
    assert_eq!(data["episodes"].as_array().map(Vec::len), Some(1));
    let link = data["episodes"][0]["link"].as_str().expect("a link");
    let (status, page) = served.get(&format!("/{link}"), limit).expect("answered");
    assert_eq!(status, 200);
    assert!(page.contains("<html"), "{page:.200}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_server_never_waits_on_a_pipe_put_where_the_results_file_was() {
    let dir = scratch("view-serve-pipe");
    let (results, _) = bench_demo(&dir);
    let folder = dir.join("live");
    std::fs::create_dir(&folder).expect("made");
    let file = folder.join("res.jsonl");
    std::fs::copy(&results, &file).expect("copied");
    let by_folder = Served::start(&folder);
    let by_name = Served::start(&file);
    // Replaced by a pipe that nobody writes to: every request is answered, more of them
    // than the server makes pages at once.
    std::fs::remove_file(&file).expect("removed");
    let made = Command::new("mkfifo").arg(&file).status();
    assert!(made.expect("mkfifo runs").success());
    let limit = Duration::from_secs(2);
    for _ in 0..6 {
        // The folder holds no results file any more.
        let (status, _) = by_folder.get("/", limit).expect("answered");
        assert_eq!(status, 200);
        // The file named is refused, named.
        let (status, why) = by_name.get("/", limit).expect("answered");
        assert_eq!(status, 500);
        assert!(why.contains("res.jsonl: not a regular file"), "{why}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A transcript of `rounds` rounds that physics can follow to its end: the demo's
/// optimal plan up to the apple on the coffee table, then the robot dog and the
/// quadrotor going back and forth for ever (an episode gone round in circles). The
/// prompts are left out, to keep it small.
fn going_round(dir: &Path, rounds: usize) -> PathBuf {
    let planned = run_demo(dir, &[]);
    let text = std::fs::read_to_string(&planned).expect("the transcript");
    let mut lines = text.lines();
    let header = lines.next().expect("a header").to_owned();
    let plan: Vec<String> = lines
        .filter(|l| l.contains(r#""type":"round""#))
        .map(str::to_owned)
        .collect();
    // Round k of the plan (from 1).
    let round = |k: usize| plan[k - 1].clone();
    let to_kitchen = round(8).replace("<living room>(2)", "<kitchen>(0)");
    let cycle = [
        to_kitchen,
        round(4),
        round(8),
        round(9),
        round(11),
        round(12),
        round(13),
        round(14),
        round(16),
        round(17),
        round(18),
    ];
    let sequence = (1..=10).map(round).chain(cycle.iter().cloned().cycle());
    let mut out = header + "\n";
    for (k, text) in sequence.take(rounds).enumerate() {
        let mut r: Value = serde_json::from_str(&text).expect("a round");
        r["step"] = (k + 1).into();
        r["done"] = false.into();
        for call in r["calls"].as_array_mut().into_iter().flatten() {
            for m in call["messages"].as_array_mut().into_iter().flatten() {
                m["content"] = "".into();
            }
        }
        out.push_str(&format!("{r}\n"));
    }
    let path = dir.join("going-round.jsonl");
    std::fs::write(&path, out).expect("written");
    path
}

#[test]
fn a_long_episode_going_round_in_circles_is_viewed_in_seconds_with_each_move_drawn() {
    let dir = scratch("view-long");
    let rounds = 3000;
    let transcript = going_round(&dir, rounds);
    let page = dir.join("long.html");
    let start = Instant::now();
    let out = coherent(&["view", utf8(&transcript), "-o", utf8(&page)]);
    let took = start.elapsed();
    eprintln!("{rounds} rounds viewed in {took:?}");
    assert!(out.status.success(), "{}", show(&out));
    // Carried out round by round in Rapier this took 45 s (15 ms a round); only the
    // rounds that are new are now, the others drawn as they were the first time.
    assert!(took < Duration::from_secs(15), "{took:?}");
    // No progress where stderr is no terminal.
    assert!(out.stderr.is_empty(), "{}", show(&out));
    let data = embedded(&page);
    let scene = &data["episodes"][0]["scene"];
    assert_eq!(scene["warning"], Value::Null, "physics follows to the end");
    let moments = scene["moments"].as_array().expect("moments");
    assert_eq!(moments.len(), rounds + 1);
    let steps = data["episodes"][0]["steps"].as_array().expect("steps");
    let at = |m: &Value, robot: i64| {
        let robots = m["robots"].as_array().expect("robots");
        let r = robots.iter().find(|r| r["id"] == robot).expect("placed");
        (
            r["at"][0].as_f64().unwrap_or(f64::NAN),
            r["at"][1].as_f64().unwrap_or(f64::NAN),
        )
    };
    // To the end, each robot's own move takes it elsewhere, and nothing else moves it
    // on the floor plan (a landing aside, which may shift it onto the surface below).
    for (k, step) in steps.iter().enumerate() {
        let entry = &step["robots"][0];
        let (actor, action) = (
            entry["robot"].as_i64().expect("a robot"),
            entry["decision"]["action"].as_str().expect("an action"),
        );
        for robot in [6, 11, 13] {
            let ((x0, y0), (x1, y1)) = (at(&moments[k], robot), at(&moments[k + 1], robot));
            let moved = (x1 - x0).hypot(y1 - y0) > 0.5;
            let own = robot == actor;
            if own && action.starts_with("[movetowards]") {
                assert!(moved, "round {}: {action}", k + 1);
            }
            if moved {
                assert!(
                    own && ["[movetowards]", "[land_on]", "[takeoff_from]"]
                        .iter()
                        .any(|verb| action.starts_with(verb)),
                    "round {}: robot {robot} moved on {action}",
                    k + 1
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_transcript_cut_in_its_last_line_shows_its_whole_rounds_and_says_so() {
    let dir = scratch("view-cut");
    let transcript = run_demo(&dir, &[]);
    let text = std::fs::read_to_string(&transcript).expect("the transcript");
    let lines: Vec<&str> = text.lines().collect();
    // Cut in the middle of the summary, then in the middle of the last round.
    for keep in [lines.len() - 1, lines.len() - 2] {
        let whole = lines[..keep].join("\n");
        let cut_line = lines[keep];
        let cut = dir.join(format!("cut-{keep}.jsonl"));
        std::fs::write(
            &cut,
            format!("{whole}\n{}", &cut_line[..cut_line.len() / 2]),
        )
        .expect("written");
        let page = dir.join(format!("cut-{keep}.html"));
        let out = coherent(&["view", utf8(&cut), "-o", utf8(&page)]);
        assert_eq!(out.status.code(), Some(0), "{}", show(&out));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains(&format!("line {} is cut short", keep + 1)),
            "{stderr}"
        );
        let data = embedded(&page);
        let episode = &data["episodes"][0];
        assert_eq!(episode["result"]["status"], "unfinished");
        let error = episode["result"]["error"].as_str().expect("why");
        assert!(error.contains("cut short"), "{error}");
        // The header and every whole round.
        let steps = episode["steps"].as_array().expect("steps");
        assert_eq!(steps.len(), keep - 1);
    }
    // A line cut anywhere but at the end is still refused, naming it.
    let mut broken = lines.clone();
    broken[2] = &lines[2][..10];
    let bad = dir.join("bad.jsonl");
    std::fs::write(&bad, broken.join("\n") + "\n").expect("written");
    let out = coherent(&["view", utf8(&bad)]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("bad.jsonl: line 3:"),
        "{}",
        show(&out)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn two_transcripts_of_different_tasks_are_not_put_side_by_side() {
    let dir = scratch("view-two-tasks");
    let a = run_demo(&dir, &[]);
    let env0 = env0();
    let args = [
        "run",
        utf8(&env0),
        "--task",
        "0",
        "--method",
        "optimal",
        "--out",
        utf8(&dir),
    ];
    let out = coherent(&args);
    let b = String::from_utf8_lossy(&out.stdout)
        .lines()
        .find_map(|l| l.strip_prefix("transcript: ").map(str::to_owned))
        .unwrap_or_else(|| panic!("{}", show(&out)));
    let page = dir.join("both.html");
    let out = coherent(&["view", utf8(&a), &b, "-o", utf8(&page)]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(utf8(&a)) && stderr.contains(&b) && stderr.contains("different tasks"),
        "{stderr}"
    );
    assert!(!page.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn two_transcripts_of_one_name_in_two_folders_get_a_page_each() {
    let dir = scratch("view-one-name");
    let (results, line) = bench_demo(&dir);
    let first = PathBuf::from(line["transcript"].as_str().expect("its transcript"));
    // Another episode, under the same file name in another folder.
    let other = run_demo(&dir.join("cmrs"), &["--method", "cmrs"]);
    let elsewhere = dir
        .join("elsewhere")
        .join(first.file_name().expect("a name"));
    std::fs::create_dir_all(elsewhere.parent().expect("a folder")).expect("made");
    std::fs::rename(&other, &elsewhere).expect("moved");
    let mut second = line.clone();
    second["method"] = "cmrs".into();
    second["transcript"] = utf8(&elsewhere).into();
    let text = std::fs::read_to_string(&results).expect("the results file");
    std::fs::write(&results, format!("{text}{second}\n")).expect("written");
    let site = dir.join("site");
    let out = coherent(&["view", utf8(&results), "-o", utf8(&site)]);
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("and 2 episode pages"),
        "{}",
        show(&out)
    );
    let index = embedded(&site.join("index.html"));
    let rows = index["episodes"].as_array().expect("rows");
    let links: Vec<&str> = rows.iter().filter_map(|r| r["link"].as_str()).collect();
    assert_eq!(links.len(), 2);
    assert_ne!(links[0], links[1]);
    // Each row's page shows its own episode.
    for (row, link) in rows.iter().zip(&links) {
        let page = embedded(&site.join(link));
        assert_eq!(page["episodes"][0]["header"]["method"], row["method"]);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_results_path_that_would_drive_the_terminal_is_shown_escaped_in_every_line() {
    let dir = scratch("view-osc");
    // A folder whose name sets the terminal's title (OSC 0).
    let folder = dir.join("runs\u{1b}]0;owned\u{7}");
    std::fs::create_dir_all(&folder).expect("made");
    let (_, mut line) = bench_demo(&dir);
    line["transcript"] = "/nonexistent/seed0/gone.jsonl".into();
    let results = folder.join("results.jsonl");
    std::fs::write(&results, format!("{line}\n")).expect("written");
    let out = coherent(&["view", utf8(&results), "-o", utf8(&dir.join("site"))]);
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("warning: no page for"), "{stderr}");
    for stream in [&out.stdout, &out.stderr] {
        assert!(!stream.contains(&0x1b), "{}", show(&out));
    }
    assert!(stderr.contains("runs\\u{1b}]0;owned\\u{7}"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn every_view_error_has_the_exit_status_of_its_kind() {
    let dir = scratch("view-status");
    // A file of coherent's formats that does not follow it: 2 (a data file).
    let transcript = run_demo(&dir, &[]);
    let text = std::fs::read_to_string(&transcript).expect("the transcript");
    let broken = dir.join("broken.jsonl");
    std::fs::write(
        &broken,
        text.replacen(r#""type":"round""#, r#""type":"roundabout""#, 1),
    )
    .expect("written");
    let out = coherent(&["view", utf8(&broken)]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("broken.jsonl: line 2:"),
        "{}",
        show(&out)
    );
    // A page that cannot be written: 2, naming where.
    let out = coherent(&["view", utf8(&transcript), "-o", "/proc/coherent.html"]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/proc/coherent.html"));
    // A results file beside a transcript: 2 (an argument that cannot be used).
    let (results, _) = bench_demo(&dir);
    let out = coherent(&["view", utf8(&transcript), utf8(&results)]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    // A port already taken: 2.
    let taken = std::net::TcpListener::bind("127.0.0.1:0").expect("a port");
    let port = taken.local_addr().expect("its address").port().to_string();
    let out = coherent(&["view", "--serve", utf8(&results), "--port", &port]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    let _ = std::fs::remove_dir_all(&dir);
}
