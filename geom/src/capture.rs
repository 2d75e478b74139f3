//! A child's output kept within a bound: the first lines, the last ones and
//! every `Error`/`Warning` line between them (up to a count), so that a
//! tool that prints hundreds of MB keeps its messages readable and ribbar's
//! memory small. Lines are split on `\n`; a line longer than
//! [`MAX_LINE_BYTES`] is cut.

use std::collections::VecDeque;
use std::io::Read;

/// The first lines kept, bytes.
pub const HEAD_BYTES: usize = 64 << 10;
/// The last lines kept, bytes.
pub const TAIL_BYTES: usize = 1 << 20;
/// `Error` and `Warning` lines kept from between head and tail.
pub const MAX_MIDDLE_LINES: usize = 200;
/// The longest line kept, bytes (the rest of it is dropped).
pub const MAX_LINE_BYTES: usize = 4096;

/// The bounded record of one output stream.
#[derive(Debug, Default)]
pub struct Capture {
    head: String,
    head_full: bool,
    middle: Vec<String>,
    tail: VecDeque<String>,
    tail_bytes: usize,
    /// Bytes of lines not kept.
    dropped: u64,
    partial: Vec<u8>,
}

impl Capture {
    /// Reads `reader` to its end.
    pub fn read_all(mut reader: impl Read) -> Capture {
        let mut capture = Capture::default();
        let mut buf = vec![0u8; 64 << 10];
        loop {
            match reader.read(&mut buf) {
                Ok(0) | Err(_) => break,
                Ok(n) => capture.push(&buf[..n]),
            }
        }
        capture.finish()
    }

    fn push(&mut self, mut bytes: &[u8]) {
        while let Some(at) = bytes.iter().position(|&b| b == b'\n') {
            self.extend_partial(&bytes[..at]);
            let line = std::mem::take(&mut self.partial);
            self.line(String::from_utf8_lossy(&line).into_owned());
            bytes = &bytes[at + 1..];
        }
        self.extend_partial(bytes);
    }

    fn extend_partial(&mut self, bytes: &[u8]) {
        let room = MAX_LINE_BYTES.saturating_sub(self.partial.len());
        self.partial
            .extend_from_slice(&bytes[..bytes.len().min(room)]);
        self.dropped += bytes.len().saturating_sub(room) as u64;
    }

    fn line(&mut self, line: String) {
        if !self.head_full && self.head.len() + line.len() < HEAD_BYTES {
            self.head.push_str(&line);
            self.head.push('\n');
            return;
        }
        self.head_full = true;
        self.tail_bytes += line.len() + 1;
        self.tail.push_back(line);
        while self.tail_bytes > TAIL_BYTES {
            let Some(old) = self.tail.pop_front() else {
                break;
            };
            self.tail_bytes -= old.len() + 1;
            let notable = old.starts_with("Error") || old.starts_with("Warning");
            if notable && self.middle.len() < MAX_MIDDLE_LINES {
                self.middle.push(old);
            } else {
                self.dropped += old.len() as u64 + 1;
            }
        }
    }

    fn finish(mut self) -> Capture {
        if !self.partial.is_empty() {
            let line = std::mem::take(&mut self.partial);
            self.line(String::from_utf8_lossy(&line).into_owned());
        }
        self
    }

    /// What was kept, in order; a line says how much was left out.
    pub fn text(&self) -> String {
        let mut out = self.head.clone();
        if self.dropped > 0 {
            out.push_str(&format!(
                "[… {} bytes of output not kept …]\n",
                self.dropped
            ));
        }
        for line in self.middle.iter().chain(&self.tail) {
            out.push_str(line);
            out.push('\n');
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 300 MB of output keeps a bounded text: its head, its tail, the
    /// error lines from between them, and the count of what was left out.
    #[test]
    fn a_flood_of_output_keeps_its_head_tail_and_errors() {
        struct Flood(u64);
        impl Read for Flood {
            fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
                if self.0 == 0 {
                    return Ok(0);
                }
                let line: &[u8] = if self.0 == 150_000 {
                    b"Error   : the middle failed\n"
                } else {
                    b"Info    : [ 10%] a line of progress that repeats itself over and over\n"
                };
                self.0 -= 1;
                let n = line.len().min(buf.len());
                buf[..n].copy_from_slice(&line[..n]);
                Ok(n)
            }
        }
        let capture = Capture::read_all(Flood(1_000_000));
        let text = capture.text();
        assert!(
            text.len() < HEAD_BYTES + TAIL_BYTES + 2 * MAX_LINE_BYTES,
            "{}",
            text.len()
        );
        assert!(text.contains("Error   : the middle failed"), "{text:.300}");
        assert!(text.contains("bytes of output not kept"));
        assert!(text.starts_with("Info    : [ 10%]"));
        let short = Capture::read_all(&b"one\ntwo"[..]).text();
        assert_eq!(short, "one\ntwo\n");
        let long = Capture::read_all(&vec![b'x'; 10 * MAX_LINE_BYTES][..]).text();
        assert!(long.contains("not kept") && long.len() < 2 * MAX_LINE_BYTES);
    }
}
