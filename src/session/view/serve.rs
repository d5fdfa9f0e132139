//! `coherent view --serve`: a results file's pages on loopback, made when asked for, so
//! that the index follows the file while a benchmark writes it.
//!
//! Routes: `/` the index (it asks `/version` every two seconds and, when the file has
//! grown, `/results.json`, and draws itself anew), `/episodes/...` an episode's page
//! (only those the file names). Nothing else is served: no file is read but the results
//! file and the transcripts its lines name. Requests must name this server's own host
//! (`127.0.0.1:PORT` or `localhost:PORT`), so that no other site's page can reach it
//! through a name that resolves to loopback.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::time::Duration;

use coherent_agents::bench::{ReadLimits, ResultLine, read_results_within};

use super::page::script_json;
use super::{Holds, holds, line_html, results, results_html};

/// Connections served at once.
const WORKERS: usize = 4;
/// The most bytes of a request's head read.
const MAX_HEAD: u64 = 8 << 10;

/// A results file as read: its lines, each one's page (when its transcript is at hand),
/// and the file's length.
type Lines = (Vec<ResultLine>, Vec<Option<String>>, u64);

/// A server bound on loopback for one results file.
#[derive(Debug)]
pub struct Server {
    listener: TcpListener,
    results: PathBuf,
    limits: ReadLimits,
}

/// The results file in `path`: the file itself, or the one results file in a folder
/// (each `.jsonl` in it read within `limits` to tell).
pub fn results_in(path: &Path, limits: ReadLimits) -> Result<PathBuf, String> {
    if !path.is_dir() {
        return Ok(path.to_owned());
    }
    let mut found = Vec::new();
    let entries = std::fs::read_dir(path).map_err(|e| format!("{}: {e}", path.display()))?;
    for entry in entries.flatten() {
        let p = entry.path();
        if p.extension().is_some_and(|x| x == "jsonl") && holds(&p, limits) == Ok(Holds::Results) {
            found.push(p);
        }
    }
    found.sort();
    match found.len() {
        1 => Ok(found.remove(0)),
        0 => Err(format!(
            "{}: no results file (*.jsonl) in it",
            path.display()
        )),
        _ => Err(format!(
            "{}: several results files, name one: {}",
            path.display(),
            found
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )),
    }
}

impl Server {
    /// Binds `127.0.0.1:port` (0: any free port) for the results file `results`, read
    /// (with its transcripts) within `limits`.
    pub fn bind(results: &Path, port: u16, limits: ReadLimits) -> Result<Server, String> {
        let listener = TcpListener::bind((Ipv4Addr::LOCALHOST, port))
            .map_err(|e| format!("127.0.0.1:{port}: {e}"))?;
        Ok(Server {
            listener,
            results: results.to_owned(),
            limits,
        })
    }

    pub fn address(&self) -> Result<SocketAddr, String> {
        self.listener.local_addr().map_err(|e| e.to_string())
    }

    /// Serves until the process ends.
    pub fn run(&self) -> Result<(), String> {
        let port = self.address()?.port();
        std::thread::scope(|scope| {
            for _ in 0..WORKERS {
                scope.spawn(|| {
                    for stream in self.listener.incoming().flatten() {
                        let _ = self.answer(stream, port);
                    }
                });
            }
        });
        Ok(())
    }

    fn answer(&self, mut stream: TcpStream, port: u16) -> std::io::Result<()> {
        stream.set_read_timeout(Some(Duration::from_secs(10)))?;
        let (method, target, host) = match read_head(&stream) {
            Ok(head) => head,
            Err(why) => return reply(&mut stream, 400, "text/plain", why.as_bytes()),
        };
        let ours = [format!("127.0.0.1:{port}"), format!("localhost:{port}")];
        if !ours.contains(&host) {
            return reply(&mut stream, 421, "text/plain", b"not this server's host");
        }
        if method != "GET" {
            return reply(&mut stream, 405, "text/plain", b"GET only");
        }
        let path = target.split('?').next().unwrap_or("");
        let body = match path {
            "/" | "/index.html" => self.index().map(|html| ("text/html; charset=utf-8", html)),
            "/version" => Ok(("text/plain", self.version())),
            "/results.json" => self.data().map(|json| ("application/json", json)),
            _ => match self.episode(path) {
                Some(page) => page.map(|html| ("text/html; charset=utf-8", html)),
                None => return reply(&mut stream, 404, "text/plain", b"no such page"),
            },
        };
        match body {
            Ok((kind, text)) => reply(&mut stream, 200, kind, text.as_bytes()),
            Err(why) => reply(&mut stream, 500, "text/plain", why.as_bytes()),
        }
    }

    /// The lines so far (none before the file exists), each with its page's name, and
    /// the file's length as read.
    fn lines(&self) -> Result<Lines, String> {
        if !self.results.exists() {
            return Ok((Vec::new(), Vec::new(), 0));
        }
        let file = read_results_within(&self.results, self.limits.results_bytes)
            .map_err(|e| e.to_string())?;
        let version = file.good_len + file.truncated_bytes;
        let lines = file.lines;
        let links = lines
            .iter()
            .map(|l| results::transcript_of(&self.results, l).map(|_| results::page_name(l)))
            .collect();
        Ok((lines, links, version))
    }

    fn index(&self) -> Result<String, String> {
        let (lines, links, version) = self.lines()?;
        results_html(&self.results, &lines, &links, Some(version))
    }

    /// What the index polls: the file's length, which grows with each line.
    fn version(&self) -> String {
        std::fs::metadata(&self.results)
            .map_or(0, |m| m.len())
            .to_string()
    }

    fn data(&self) -> Result<String, String> {
        let (lines, links, version) = self.lines()?;
        script_json(&results::view(&self.results, &lines, &links, Some(version)))
    }

    /// The page at `path` (`/episodes/...`), if a line of the file has that page.
    fn episode(&self, path: &str) -> Option<Result<String, String>> {
        let name = path.strip_prefix('/')?;
        let (lines, _, _) = self.lines().ok()?;
        let line = lines.iter().find(|l| results::page_name(l) == name)?;
        Some(line_html(&self.results, line, self.limits.transcript_bytes))
    }
}

/// The request line's method and target, and the `Host` header.
fn read_head(stream: &TcpStream) -> Result<(String, String, String), String> {
    let mut reader = BufReader::new(stream.take(MAX_HEAD));
    let mut first = String::new();
    reader
        .read_line(&mut first)
        .map_err(|e| format!("bad request: {e}"))?;
    let mut parts = first.split_whitespace();
    let (Some(method), Some(target)) = (parts.next(), parts.next()) else {
        return Err("bad request line".into());
    };
    let mut host = String::new();
    loop {
        let mut line = String::new();
        let n = reader
            .read_line(&mut line)
            .map_err(|e| format!("bad request: {e}"))?;
        if n == 0 || !line.ends_with('\n') {
            return Err("the request's head is cut short or too long".into());
        }
        let line = line.trim_end();
        if line.is_empty() {
            break;
        }
        if let Some((name, value)) = line.split_once(':')
            && name.eq_ignore_ascii_case("host")
        {
            value.trim().clone_into(&mut host);
        }
    }
    Ok((method.to_owned(), target.to_owned(), host))
}

fn reply(stream: &mut TcpStream, status: u16, kind: &str, body: &[u8]) -> std::io::Result<()> {
    let reason = match status {
        200 => "OK",
        400 => "Bad Request",
        404 => "Not Found",
        405 => "Method Not Allowed",
        421 => "Misdirected Request",
        _ => "Internal Server Error",
    };
    let head = format!(
        "HTTP/1.1 {status} {reason}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\nConnection: close\r\n\r\n",
        body.len()
    );
    stream.write_all(head.as_bytes())?;
    stream.write_all(body)?;
    stream.flush()
}
