//! Reading the files the program is given, with a bound on what it holds: a file is read
//! up to a limit, so that a huge file, a device that never ends (`/dev/zero`) or a
//! folder given as a file ends in an error that names the file and the limit instead of
//! taking every byte of memory. Each reader has its limit next to it; `docs/architecture.md`
//! ("Limits on what is read") lists them all.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use crate::error::{Error, Result};

/// One mebibyte, the unit of the limits' flags.
pub const MIB: u64 = 1 << 20;

/// How much of a kind of file may be read, and how to say so.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limit {
    pub bytes: u64,
    /// The kind of file, in words: `a task file`.
    pub what: &'static str,
    /// How a user allows more (`--max-transcript-mib`), when they may.
    pub raise: Option<&'static str>,
}

impl Limit {
    /// The error for a file of this kind that holds more than the limit.
    pub fn exceeded(&self, file: &Path) -> Error {
        Error::Io {
            file: file.display().to_string(),
            message: format!(
                "more than {}, the most {} may hold{}",
                size(self.bytes),
                self.what,
                self.how_to_raise()
            ),
        }
    }

    /// ` (raise it with ...)`, or nothing for a limit users may not raise.
    fn how_to_raise(&self) -> String {
        self.raise
            .map_or_else(String::new, |how| format!(" (raise it with {how})"))
    }
}

/// `bytes` as a size people read: `64 MiB`, `512 KiB`, `100 bytes`.
pub fn size(bytes: u64) -> String {
    if bytes >= MIB && bytes.is_multiple_of(MIB) {
        format!("{} MiB", bytes / MIB)
    } else if bytes >= 1024 && bytes.is_multiple_of(1024) {
        format!("{} KiB", bytes / 1024)
    } else {
        format!("{bytes} bytes")
    }
}

fn io_error(path: &Path, e: &std::io::Error) -> Error {
    Error::Io {
        file: path.display().to_string(),
        message: e.to_string(),
    }
}

/// What a reader opens besides a regular file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Opens {
    /// A pipe or a device too, read up to the limit: what a user names on the command
    /// line may be one (`/dev/stdin`, `<(...)`).
    #[default]
    Anything,
    /// Regular files only: a server reading files others may replace must never wait
    /// on a pipe that nobody writes to.
    RegularFiles,
}

/// Opens `path` to read, refusing a folder (which opens, but reads as an error later)
/// and, when `opens` says so, anything but a regular file. The open itself never
/// waits: `open(2)` of a FIFO without a writer blocks until one comes, so the file is
/// opened non-blocking and its kind taken from what was opened (no window between a
/// look and the open), then made blocking again to read a pipe as before.
fn open(path: &Path, opens: Opens) -> Result<(File, std::fs::Metadata)> {
    use rustix::fs::{Mode, OFlags};
    let flags = OFlags::RDONLY | OFlags::NONBLOCK | OFlags::CLOEXEC;
    let fd = rustix::fs::open(path, flags, Mode::empty())
        .map_err(|e| io_error(path, &std::io::Error::from(e)))?;
    let file = File::from(fd);
    let meta = file.metadata().map_err(|e| io_error(path, &e))?;
    let refuse = |message: &str| {
        Err(Error::Io {
            file: path.display().to_string(),
            message: message.to_owned(),
        })
    };
    if meta.is_dir() {
        return refuse("is a folder, not a file");
    }
    if !meta.is_file() {
        if opens == Opens::RegularFiles {
            return refuse("not a regular file (a pipe, a device?): it is not read here");
        }
        rustix::fs::fcntl_getfl(&file)
            .and_then(|now| rustix::fs::fcntl_setfl(&file, now - OFlags::NONBLOCK))
            .map_err(|e| io_error(path, &std::io::Error::from(e)))?;
    }
    Ok((file, meta))
}

/// The whole file at `path`, refused when it holds more than `limit`: a regular file by
/// its size before anything is read, anything else (a pipe, a device) once the limit
/// is passed.
pub fn read(path: &Path, limit: &Limit) -> Result<Vec<u8>> {
    let (file, meta) = open(path, Opens::Anything)?;
    if meta.is_file() && meta.len() > limit.bytes {
        return Err(limit.exceeded(path));
    }
    let mut bytes = Vec::new();
    file.take(limit.bytes.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| io_error(path, &e))?;
    if bytes.len() as u64 > limit.bytes {
        return Err(limit.exceeded(path));
    }
    Ok(bytes)
}

/// One line of a [`Lines`] file.
#[derive(Debug)]
pub struct Line<'a> {
    /// From 1.
    pub number: usize,
    /// The line's bytes, its newline included when it has one.
    pub bytes: &'a [u8],
    /// The offset of the line's first byte in the file.
    pub start: u64,
}

impl Line<'_> {
    /// Whether the line ends with a newline (the last one of a file may not).
    pub fn complete(&self) -> bool {
        self.bytes.last() == Some(&b'\n')
    }

    /// The offset just after the line.
    pub fn end(&self) -> u64 {
        self.start + self.bytes.len() as u64
    }
}

/// The lines of a file, each at most `line` long and all of them at most `total`: only
/// one line is held at a time, and no more of it than the limits allow.
#[derive(Debug)]
pub struct Lines {
    reader: BufReader<File>,
    path: std::path::PathBuf,
    line: Limit,
    total: Limit,
    buf: Vec<u8>,
    offset: u64,
    number: usize,
}

impl Lines {
    /// Opens `path`; a regular file larger than `total` is refused at once.
    pub fn open(path: &Path, line: Limit, total: Limit) -> Result<Lines> {
        Lines::open_as(path, line, total, Opens::Anything)
    }

    /// [`Lines::open`], opening only what `opens` allows.
    pub fn open_as(path: &Path, line: Limit, total: Limit, opens: Opens) -> Result<Lines> {
        let (file, meta) = open(path, opens)?;
        if meta.is_file() && meta.len() > total.bytes {
            return Err(total.exceeded(path));
        }
        Ok(Lines {
            reader: BufReader::new(file),
            path: path.to_owned(),
            line,
            total,
            buf: Vec::new(),
            offset: 0,
            number: 0,
        })
    }

    /// The next line, `None` at the end of the file. A line longer than the line limit
    /// is an error naming its number; a file longer than the total limit, one naming it.
    pub fn next_line(&mut self) -> Result<Option<Line<'_>>> {
        self.buf.clear();
        let left = self.total.bytes.saturating_sub(self.offset);
        let cap = self.line.bytes.min(left).saturating_add(1);
        let read = (&mut self.reader)
            .take(cap)
            .read_until(b'\n', &mut self.buf)
            .map_err(|e| io_error(&self.path, &e))?;
        if read == 0 {
            return Ok(None);
        }
        self.number += 1;
        let start = self.offset;
        self.offset += read as u64;
        if self.offset > self.total.bytes {
            return Err(self.total.exceeded(&self.path));
        }
        let content = self.buf.len() - usize::from(self.buf.last() == Some(&b'\n'));
        if content as u64 > self.line.bytes {
            return Err(Error::Io {
                file: self.path.display().to_string(),
                message: format!(
                    "line {}: longer than {}, the most a line of {} may hold{}",
                    self.number,
                    size(self.line.bytes),
                    self.line.what,
                    self.line.how_to_raise()
                ),
            });
        }
        Ok(Some(Line {
            number: self.number,
            bytes: &self.buf,
            start,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limit(bytes: u64) -> Limit {
        Limit {
            bytes,
            what: "a test file",
            raise: Some("--more"),
        }
    }

    fn scratch(name: &str, text: &[u8]) -> std::path::PathBuf {
        let path =
            std::env::temp_dir().join(format!("coherent-files-{}-{name}", std::process::id()));
        std::fs::write(&path, text).expect("a scratch file");
        path
    }

    #[test]
    fn sizes_read_as_people_write_them() {
        assert_eq!(size(64 * MIB), "64 MiB");
        assert_eq!(size(512 * 1024), "512 KiB");
        assert_eq!(size(1000), "1000 bytes");
    }

    #[test]
    fn a_file_over_its_limit_is_refused_naming_the_file_and_the_limit() {
        let path = scratch("whole", b"0123456789");
        assert_eq!(
            read(&path, &limit(10)).expect("at the limit"),
            b"0123456789"
        );
        let e = read(&path, &limit(9)).expect_err("over it").to_string();
        assert_eq!(
            e,
            format!(
                "{}: more than 9 bytes, the most a test file may hold (raise it with --more)",
                path.display()
            )
        );
        std::fs::remove_file(&path).expect("removed");
        // A device that never ends stops at the limit.
        let e = read(Path::new("/dev/zero"), &limit(MIB)).expect_err("endless");
        assert!(
            e.to_string().starts_with("/dev/zero: more than 1 MiB"),
            "{e}"
        );
        let e = read(&std::env::temp_dir(), &limit(MIB)).expect_err("a folder");
        assert!(e.to_string().ends_with("is a folder, not a file"), "{e}");
    }

    #[test]
    fn lines_keep_their_offsets_and_stop_at_either_limit() {
        let path = scratch("lines", b"ab\ncde\nf");
        let mut lines = Lines::open(&path, limit(3), limit(100)).expect("opens");
        let mut seen = Vec::new();
        while let Some(l) = lines.next_line().expect("within the limits") {
            seen.push((l.number, l.bytes.to_vec(), l.start, l.complete()));
        }
        assert_eq!(
            seen,
            [
                (1, b"ab\n".to_vec(), 0, true),
                (2, b"cde\n".to_vec(), 3, true),
                (3, b"f".to_vec(), 7, false)
            ]
        );
        let mut short = Lines::open(&path, limit(2), limit(100)).expect("opens");
        short.next_line().expect("line 1 fits");
        let e = short.next_line().expect_err("line 2 does not").to_string();
        assert!(e.ends_with("line 2: longer than 2 bytes, the most a line of a test file may hold (raise it with --more)"), "{e}");
        let e = Lines::open(&path, limit(3), limit(7)).expect_err("8 bytes in all");
        assert!(e.to_string().contains("more than 7 bytes"), "{e}");
        std::fs::remove_file(&path).expect("removed");
        let mut endless =
            Lines::open(Path::new("/dev/zero"), limit(MIB), limit(4 * MIB)).expect("opens");
        let e = endless.next_line().expect_err("one endless line");
        assert!(e.to_string().contains("line 1: longer than 1 MiB"), "{e}");
    }

    #[test]
    fn a_fifo_without_a_writer_is_opened_without_waiting_or_refused() {
        let path = std::env::temp_dir().join(format!("coherent-files-{}-fifo", std::process::id()));
        let _ = std::fs::remove_file(&path);
        let made = std::process::Command::new("mkfifo").arg(&path).status();
        assert!(made.expect("mkfifo runs").success());
        // Opened as before (read as empty: nobody writes), where open(2) used to wait
        // for a writer for ever.
        let mut lines = Lines::open(&path, limit(10), limit(10)).expect("opens");
        assert!(lines.next_line().expect("reads").is_none());
        let e = Lines::open_as(&path, limit(10), limit(10), Opens::RegularFiles)
            .expect_err("no regular file");
        assert!(e.to_string().contains("not a regular file"), "{e}");
        std::fs::remove_file(&path).expect("removed");
        let e = Lines::open_as(
            Path::new("/dev/zero"),
            limit(10),
            limit(10),
            Opens::RegularFiles,
        )
        .expect_err("a device");
        assert!(e.to_string().contains("not a regular file"), "{e}");
    }
}
