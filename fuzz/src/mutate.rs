//! A small, seeded byte-level mutation engine.
//!
//! Each call of [`Mutator::mutate`] stacks one to four operations on a copy
//! of a corpus entry: bit flips, random bytes, inserts, deletes, duplicated
//! ranges, splices and cross-overs with other corpus entries, interesting
//! binary integers (little- and big-endian) written over the input, textual
//! numbers (`-1`, `1e300`, `NaN`, `18446744073709551616`, ...) written over a
//! run of digits, and tokens of the target's dictionary inserted at random.
//! The engine is deterministic for a given seed and corpus.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Binary integers worth trying (boundaries, sign bits, powers of two).
const INTERESTING: [u64; 24] = [
    0,
    1,
    2,
    3,
    4,
    7,
    8,
    16,
    0x7f,
    0x80,
    0xff,
    0x100,
    0x7fff,
    0x8000,
    0xffff,
    0x1_0000,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_ffff,
    0x1_0000_0000,
    0x7fff_ffff_ffff_ffff,
    0x8000_0000_0000_0000,
    u64::MAX,
    u64::MAX - 1,
];

/// Numbers as text, written over a run of ASCII digits.
const INTERESTING_TEXT: [&str; 20] = [
    "0",
    "-0",
    "-1",
    "1e300",
    "-1e300",
    "1e-300",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "Infinity",
    "4294967295",
    "4294967296",
    "2147483648",
    "-2147483649",
    "9223372036854775807",
    "18446744073709551616",
    "99999999999999999999999",
    "1e5",
    "0.000000001",
];

/// A seeded mutator.
#[derive(Debug, Clone)]
pub struct Mutator {
    rng: ChaCha8Rng,
    max_len: usize,
}

impl Mutator {
    /// A mutator whose outputs never exceed `max_len` bytes.
    pub fn new(seed: u64, max_len: usize) -> Self {
        Self {
            rng: ChaCha8Rng::seed_from_u64(seed),
            max_len: max_len.max(1),
        }
    }

    /// A uniform index below `n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        self.rng.random_range(0..n.max(1))
    }

    /// A new input: a copy of `corpus[index]` with one to four stacked
    /// mutations. `dictionary` holds tokens of the target's format.
    pub fn mutate(&mut self, corpus: &[Vec<u8>], index: usize, dictionary: &[&[u8]]) -> Vec<u8> {
        let mut data = corpus.get(index).cloned().unwrap_or_default();
        let rounds = 1 + self.below(4);
        for _ in 0..rounds {
            self.mutate_once(&mut data, corpus, dictionary);
        }
        data.truncate(self.max_len);
        data
    }

    fn mutate_once(&mut self, data: &mut Vec<u8>, corpus: &[Vec<u8>], dictionary: &[&[u8]]) {
        if data.is_empty() {
            let n = 1 + self.below(16);
            data.extend((0..n).map(|_| self.rng.random::<u8>()));
            return;
        }
        match self.below(11) {
            0 => {
                let i = self.below(data.len());
                data[i] ^= 1 << self.below(8);
            }
            1 => {
                let i = self.below(data.len());
                data[i] = self.rng.random();
            }
            2 => {
                let i = self.below(data.len() + 1);
                let n = 1 + self.below(8);
                let bytes: Vec<u8> = (0..n).map(|_| self.rng.random()).collect();
                data.splice(i..i, bytes);
            }
            3 => {
                let (a, b) = self.range(data.len());
                data.drain(a..b);
            }
            4 => {
                let (a, b) = self.range(data.len());
                let copy = data[a..b].to_vec();
                let at = self.below(data.len() + 1);
                data.splice(at..at, copy);
            }
            5 => self.splice_other(data, corpus),
            6 => self.cross_over(data, corpus),
            7 => self.interesting_int(data),
            8 | 9 => self.interesting_text(data),
            _ => {
                if dictionary.is_empty() {
                    self.interesting_int(data);
                } else {
                    let token = dictionary[self.below(dictionary.len())];
                    let at = self.below(data.len() + 1);
                    if self.rng.random_bool(0.5) {
                        data.splice(at..at, token.iter().copied());
                    } else {
                        let end = (at + token.len()).min(data.len());
                        data.splice(at..end, token.iter().copied());
                    }
                }
            }
        }
    }

    /// A non-empty range `a..b` inside `0..len` (`len > 0`), short more often
    /// than long.
    fn range(&mut self, len: usize) -> (usize, usize) {
        let a = self.below(len);
        let max = if self.rng.random_bool(0.8) {
            16.min(len - a)
        } else {
            len - a
        };
        let n = 1 + self.below(max);
        (a, a + n)
    }

    /// Inserts or overwrites with a range of another corpus entry.
    fn splice_other(&mut self, data: &mut Vec<u8>, corpus: &[Vec<u8>]) {
        let other = &corpus[self.below(corpus.len())];
        if other.is_empty() {
            return;
        }
        let (a, b) = self.range(other.len());
        let at = self.below(data.len() + 1);
        if self.rng.random_bool(0.5) {
            data.splice(at..at, other[a..b].iter().copied());
        } else {
            let end = (at + (b - a)).min(data.len());
            data.splice(at..end, other[a..b].iter().copied());
        }
    }

    /// A head of `data` followed by a tail of another entry.
    fn cross_over(&mut self, data: &mut Vec<u8>, corpus: &[Vec<u8>]) {
        let other = &corpus[self.below(corpus.len())];
        let cut = self.below(data.len() + 1);
        let from = self.below(other.len() + 1);
        data.truncate(cut);
        data.extend_from_slice(&other[from..]);
    }

    /// Overwrites 1, 2, 4 or 8 bytes with an interesting integer.
    fn interesting_int(&mut self, data: &mut [u8]) {
        let width = [1usize, 2, 4, 8][self.below(4)];
        if data.len() < width {
            return;
        }
        let mut v = INTERESTING[self.below(INTERESTING.len())];
        if self.rng.random_bool(0.2) {
            v = v.wrapping_neg();
        }
        let at = self.below(data.len() - width + 1);
        let (le, be) = (v.to_le_bytes(), v.to_be_bytes());
        let src = if self.rng.random_bool(0.5) {
            &le[..width]
        } else {
            &be[8 - width..]
        };
        data[at..at + width].copy_from_slice(src);
    }

    /// Replaces the run of ASCII digits around a random position with a
    /// number as text (or inserts one when there is no digit).
    fn interesting_text(&mut self, data: &mut Vec<u8>) {
        let text = INTERESTING_TEXT[self.below(INTERESTING_TEXT.len())].as_bytes();
        let start = self.below(data.len());
        let Some(d) = data[start..]
            .iter()
            .position(u8::is_ascii_digit)
            .map(|p| p + start)
        else {
            let at = self.below(data.len() + 1);
            data.splice(at..at, text.iter().copied());
            return;
        };
        let mut a = d;
        while a > 0 && matches!(data[a - 1], b'0'..=b'9' | b'.' | b'-' | b'e' | b'E' | b'+') {
            a -= 1;
        }
        let mut b = d;
        while b < data.len() && matches!(data[b], b'0'..=b'9' | b'.' | b'e' | b'E' | b'+' | b'-') {
            b += 1;
        }
        data.splice(a..b, text.iter().copied());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deterministic_and_bounded() {
        let corpus = vec![b"DIMENSION: 12\n1 2 3".to_vec(), vec![0u8; 40]];
        let mut a = Mutator::new(7, 64);
        let mut b = Mutator::new(7, 64);
        let mut changed = 0;
        for i in 0..2000 {
            let x = a.mutate(&corpus, i % 2, &[b"EOF"]);
            assert_eq!(x, b.mutate(&corpus, i % 2, &[b"EOF"]));
            assert!(x.len() <= 64);
            changed += usize::from(x != corpus[i % 2]);
        }
        assert!(changed > 1900, "{changed}");
    }
}
