//! `coherent view --serve`: a results file's pages on loopback, made when asked for, so
//! that the index follows the file while a benchmark writes it.
//!
//! Routes: `/` the index (it asks `/version` every two seconds and, when the file has
//! grown, `/results.json`, and draws itself anew), `/episodes/...` an episode's page
//! (only those the file names). Nothing else is served: no file is read but the results
//! file and the transcripts its lines name, and only regular files (a pipe nobody
//! writes to would hold a request for ever). Requests must name this server's own host
//! (`127.0.0.1:PORT` or `localhost:PORT`), so that no other site's page can reach it
//! through a name that resolves to loopback.
//!
//! Which file is served is decided at each request: the file named, or the one results
//! file in the folder named, which a benchmark may make after the server started.
//!
//! Each connection has a thread of its own, so that a client that is slow to ask or to
//! take its answer holds only its own connection, never the others', and each has its
//! time limits: the whole request head within [`HEAD_TIME`], the whole reply within
//! [`REPLY_TIME`]. At most [`MAX_CONNECTIONS`] are open at once (more are told the
//! server is busy), and [`BUILDERS`] pages are made at once (each takes a core).

use std::io::{self, BufRead, BufReader, Read, Write};
use std::net::{Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex, PoisonError};
use std::time::{Duration, Instant};

use coherent_agents::bench::{ReadLimits, ResultLine, read_results_opening};
use coherent_core::files::Opens;

use super::page::script_json;
use super::pages::results_html;
use super::read::{Holds, holds};
use super::results;
use super::site::line_html;
use crate::session::{Error, Result};

/// Connections open at once; a connection beyond is answered 503 at once.
pub const MAX_CONNECTIONS: usize = 64;
/// Pages made at once.
pub const BUILDERS: usize = 4;
/// The longest a client may take to send its whole request head.
pub const HEAD_TIME: Duration = Duration::from_secs(5);
/// The longest a client may take to receive a whole reply, from its first byte (an
/// index of a million episodes is a few hundred MB, which loopback carries to a browser
/// in about a second).
pub const REPLY_TIME: Duration = Duration::from_secs(10);
/// The most bytes of a request's head read.
const MAX_HEAD: u64 = 8 << 10;

/// A results file as read: its lines, each one's page (when its transcript is at hand),
/// and the file's length.
type Lines = (Vec<ResultLine>, Vec<Option<String>>, u64);

/// A server bound on loopback for one results file.
#[derive(Debug)]
pub struct Server {
    listener: TcpListener,
    /// The results file, or the folder it is (or will be) in.
    served: PathBuf,
    limits: ReadLimits,
}

impl Server {
    /// Binds `127.0.0.1:port` (0: any free port) for the results file `served`, or the
    /// one in the folder `served`, read (with its transcripts) within `limits`. A folder
    /// with several results files is refused now; one with none yet is served empty
    /// until a benchmark writes one.
    pub fn bind(served: &Path, port: u16, limits: ReadLimits) -> Result<Server> {
        let server = Server {
            listener: TcpListener::bind((Ipv4Addr::LOCALHOST, port))
                .map_err(|e| Error::Invalid(format!("127.0.0.1:{port}: {e}")))?,
            served: served.to_owned(),
            limits,
        };
        server.results()?;
        Ok(server)
    }

    pub fn address(&self) -> Result<SocketAddr> {
        self.listener
            .local_addr()
            .map_err(|e| Error::Internal(format!("the server's address: {e}")))
    }

    /// The results file served now: the file named, or the one results file in the
    /// folder named (each `.jsonl` in it read within the limits to tell); none while
    /// there is none.
    pub fn results(&self) -> Result<Option<PathBuf>> {
        let path = &self.served;
        if !path.is_dir() {
            return Ok(path.exists().then(|| path.clone()));
        }
        let mut found = Vec::new();
        let entries = std::fs::read_dir(path).map_err(|e| Error::File {
            file: path.display().to_string(),
            line: None,
            message: e.to_string(),
        })?;
        for entry in entries.flatten() {
            let p = entry.path();
            if p.extension().is_some_and(|x| x == "jsonl")
                && holds(&p, self.limits, Opens::RegularFiles).ok() == Some(Holds::Results)
            {
                found.push(p);
            }
        }
        found.sort();
        match found.len() {
            0 | 1 => Ok(found.pop()),
            _ => Err(Error::Invalid(format!(
                "{}: several results files, name one: {}",
                path.display(),
                found
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))),
        }
    }

    /// Serves until the process ends.
    pub fn run(&self) -> Result<()> {
        let port = self.address()?.port();
        let open = AtomicUsize::new(0);
        let builders = Builders::new(BUILDERS);
        let (open, builders) = (&open, &builders);
        std::thread::scope(|scope| {
            for stream in self.listener.incoming() {
                let Ok(stream) = stream else {
                    // Out of file descriptors, most likely: let some connections end.
                    std::thread::sleep(Duration::from_millis(10));
                    continue;
                };
                if open.load(Ordering::Acquire) >= MAX_CONNECTIONS {
                    // A reply this small fits the socket's buffer: no wait.
                    let busy = Duration::from_secs(1);
                    let _ = reply(&stream, busy, 503, "text/plain", b"busy: try again");
                    continue;
                }
                open.fetch_add(1, Ordering::AcqRel);
                let spawned = std::thread::Builder::new().spawn_scoped(scope, move || {
                    let _ = self.answer(&stream, port, builders);
                    open.fetch_sub(1, Ordering::AcqRel);
                });
                if spawned.is_err() {
                    open.fetch_sub(1, Ordering::AcqRel);
                }
            }
        });
        Ok(())
    }

    fn answer(&self, stream: &TcpStream, port: u16, builders: &Builders) -> io::Result<()> {
        let head = read_head(Deadline {
            stream,
            until: Instant::now() + HEAD_TIME,
        });
        let Head {
            method,
            target,
            host,
        } = match head {
            Ok(head) => head,
            Err(why) => {
                let why = why.to_string();
                return reply(stream, REPLY_TIME, 400, "text/plain", why.as_bytes());
            }
        };
        let ours = [format!("127.0.0.1:{port}"), format!("localhost:{port}")];
        if !ours.contains(&host) {
            return reply(
                stream,
                REPLY_TIME,
                421,
                "text/plain",
                b"not this server's host",
            );
        }
        if method != "GET" {
            return reply(stream, REPLY_TIME, 405, "text/plain", b"GET only");
        }
        let path = target.split('?').next().unwrap_or("");
        let html = "text/html; charset=utf-8";
        let body = match path {
            "/version" => self.version().map(|v| ("text/plain", v)),
            "/" | "/index.html" => builders.one(|| self.index()).map(|page| (html, page)),
            "/results.json" => builders
                .one(|| self.data())
                .map(|json| ("application/json", json)),
            _ => match builders.one(|| self.episode(path)) {
                Some(page) => page.map(|page| (html, page)),
                None => return reply(stream, REPLY_TIME, 404, "text/plain", b"no such page"),
            },
        };
        match body {
            Ok((kind, text)) => reply(stream, REPLY_TIME, 200, kind, text.as_bytes()),
            Err(why) => reply(
                stream,
                REPLY_TIME,
                500,
                "text/plain",
                why.to_string().as_bytes(),
            ),
        }
    }

    /// The file served now (none yet: no lines), its lines, each with its page's name
    /// when its transcript is at hand, and the file's length as read.
    fn lines(&self) -> Result<(Option<PathBuf>, Lines)> {
        let Some(file) = self.results()? else {
            return Ok((None, (Vec::new(), Vec::new(), 0)));
        };
        let read = read_results_opening(&file, self.limits.results_bytes, Opens::RegularFiles)?;
        let version = read.good_len + read.truncated_bytes;
        let names = results::page_names(&read.lines);
        let links = read
            .lines
            .iter()
            .zip(names)
            .map(|(l, name)| results::transcript_of(&file, l).map(|_| name))
            .collect();
        Ok((Some(file), (read.lines, links, version)))
    }

    fn index(&self) -> Result<String> {
        let (file, (lines, links, version)) = self.lines()?;
        let file = file.unwrap_or_else(|| self.served.clone());
        results_html(&file, &lines, &links, Some(version))
    }

    /// What the index polls: the file's length, which grows with each line.
    fn version(&self) -> Result<String> {
        let length = self
            .results()?
            .and_then(|file| std::fs::metadata(file).ok())
            .map_or(0, |m| m.len());
        Ok(length.to_string())
    }

    fn data(&self) -> Result<String> {
        let (file, (lines, links, version)) = self.lines()?;
        let file = file.unwrap_or_else(|| self.served.clone());
        script_json(&results::view(&file, &lines, &links, Some(version)))
    }

    /// The page at `path` (`/episodes/...`), if a line of the file has that page.
    fn episode(&self, path: &str) -> Option<Result<String>> {
        let name = path.strip_prefix('/')?;
        let (file, (lines, _, _)) = match self.lines() {
            Ok(read) => read,
            Err(e) => return Some(Err(e)),
        };
        let file = file?;
        let names = results::page_names(&lines);
        let i = names.iter().position(|n| n == name)?;
        let opens = Opens::RegularFiles;
        Some(line_html(
            &file,
            &lines[i],
            self.limits.transcript_bytes,
            opens,
        ))
    }
}

/// At most so many pages made at once; the others wait their turn.
struct Builders {
    free: Mutex<usize>,
    freed: Condvar,
}

impl Builders {
    fn new(n: usize) -> Builders {
        Builders {
            free: Mutex::new(n),
            freed: Condvar::new(),
        }
    }

    /// `make`'s result, made when a builder is free.
    fn one<T>(&self, make: impl FnOnce() -> T) -> T {
        let mut free = self.free.lock().unwrap_or_else(PoisonError::into_inner);
        while *free == 0 {
            free = self
                .freed
                .wait(free)
                .unwrap_or_else(PoisonError::into_inner);
        }
        *free -= 1;
        drop(free);
        // Given back even if `make` panics.
        let _back = Back(self);
        make()
    }
}

/// Gives a builder back when dropped.
struct Back<'a>(&'a Builders);

impl Drop for Back<'_> {
    fn drop(&mut self) {
        *self.0.free.lock().unwrap_or_else(PoisonError::into_inner) += 1;
        self.0.freed.notify_one();
    }
}

/// A connection whose reads and writes must all be over by `until`: its socket's time
/// limit is set to the time left before each call, so that a client that sends or takes
/// a byte at a time cannot stretch a request or a reply beyond it.
struct Deadline<'a> {
    stream: &'a TcpStream,
    until: Instant,
}

impl Deadline<'_> {
    fn left(&self) -> io::Result<Duration> {
        let left = self.until.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(io::Error::new(io::ErrorKind::TimedOut, "out of time"));
        }
        Ok(left)
    }
}

impl Read for Deadline<'_> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        self.stream.set_read_timeout(Some(self.left()?))?;
        (&mut &*self.stream).read(buf)
    }
}

impl Write for Deadline<'_> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.stream.set_write_timeout(Some(self.left()?))?;
        (&mut &*self.stream).write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        (&mut &*self.stream).flush()
    }
}

/// What a request asks: the request line's method and target, and the `Host` header.
struct Head {
    method: String,
    target: String,
    host: String,
}

/// The request's head, or why it is no request (a client's, so `Error::Invalid`).
fn read_head(connection: Deadline<'_>) -> Result<Head> {
    let bad = |why: String| Error::Invalid(format!("bad request: {why}"));
    let mut reader = BufReader::new(connection.take(MAX_HEAD));
    let mut first = String::new();
    reader
        .read_line(&mut first)
        .map_err(|e| bad(e.to_string()))?;
    let mut parts = first.split_whitespace();
    let (Some(method), Some(target)) = (parts.next(), parts.next()) else {
        return Err(bad("no request line".into()));
    };
    let mut host = String::new();
    loop {
        let mut line = String::new();
        let n = reader
            .read_line(&mut line)
            .map_err(|e| bad(e.to_string()))?;
        if n == 0 || !line.ends_with('\n') {
            return Err(bad("the head is cut short or too long".into()));
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
    Ok(Head {
        method: method.to_owned(),
        target: target.to_owned(),
        host,
    })
}

/// Sends a whole reply within `limit`.
fn reply(
    stream: &TcpStream,
    limit: Duration,
    status: u16,
    kind: &str,
    body: &[u8],
) -> io::Result<()> {
    let reason = match status {
        200 => "OK",
        400 => "Bad Request",
        404 => "Not Found",
        405 => "Method Not Allowed",
        421 => "Misdirected Request",
        503 => "Service Unavailable",
        _ => "Internal Server Error",
    };
    let head = format!(
        "HTTP/1.1 {status} {reason}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\nConnection: close\r\n\r\n",
        body.len()
    );
    let mut out = Deadline {
        stream,
        until: Instant::now() + limit,
    };
    out.write_all(head.as_bytes())?;
    out.write_all(body)?;
    out.flush()
}
