//! The generator's random numbers: one small, seeded generator (SplitMix64, Steele,
//! Lea and Flood, *Fast splittable pseudorandom number generators*, OOPSLA 2014), and
//! seeds derived from a run's seed and a label by mixing, so that a scene or a candidate
//! task draws the same numbers whatever else is drawn before it, in any thread.
//!
//! Nothing here depends on the standard library's hashers, whose output may change
//! between Rust versions: the same command and version must write the same bytes.

/// The golden-ratio increment of SplitMix64.
const GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

/// SplitMix64's finaliser: a bijection of 64-bit words that spreads every input bit
/// over every output bit.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The seed of the stream `label`, `index` of a run seeded `seed`: its scenes
/// (`"scene"`, scene number) and its candidate tasks (`"task"`, draw number) each draw
/// from their own stream.
pub fn seed_of(seed: u64, label: &str, index: u64) -> u64 {
    let mut h = mix(seed ^ GAMMA);
    for b in label.bytes() {
        h = mix(h ^ u64::from(b));
    }
    mix(h ^ mix(index.wrapping_add(GAMMA)))
}

/// A seeded stream of random numbers.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
}

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng { state: seed }
    }

    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GAMMA);
        mix(self.state)
    }

    /// A number in `0..n` (`n` > 0), without the bias of a plain remainder.
    pub fn below(&mut self, n: usize) -> usize {
        let n = n as u64;
        // The largest multiple of n that fits: draws at or above it are drawn again.
        let zone = u64::MAX - u64::MAX % n;
        loop {
            let x = self.next_u64();
            if x < zone {
                return (x % n) as usize;
            }
        }
    }

    /// A number in `lo..=hi`.
    pub fn between(&mut self, lo: usize, hi: usize) -> usize {
        lo + self.below(hi - lo + 1)
    }

    /// A number in `[0, 1)`, from the top 53 bits.
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A length in `[lo, hi]`, on a 10 cm grid: scenes are laid out in round numbers.
    pub fn decimetres(&mut self, lo: f32, hi: f32) -> f32 {
        let (a, b) = ((lo * 10.0).round() as usize, (hi * 10.0).round() as usize);
        self.between(a, b.max(a)) as f32 / 10.0
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }

    /// One element of a non-empty slice.
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }

    /// An index drawn with the given weights (not all zero).
    pub fn weighted(&mut self, weights: &[f64]) -> usize {
        let total: f64 = weights.iter().sum();
        let mut x = self.unit() * total;
        for (i, w) in weights.iter().enumerate() {
            if x < *w {
                return i;
            }
            x -= w;
        }
        weights.iter().rposition(|w| *w > 0.0).unwrap_or(0)
    }

    /// The slice in a random order (Fisher and Yates).
    pub fn shuffle<T>(&mut self, items: &mut [T]) {
        for i in (1..items.len()).rev() {
            items.swap(i, self.below(i + 1));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_fixed_and_distinct() {
        // The same label and index give the same stream; another index another one.
        assert_eq!(seed_of(7, "task", 3), seed_of(7, "task", 3));
        assert_ne!(seed_of(7, "task", 3), seed_of(7, "task", 4));
        assert_ne!(seed_of(7, "task", 3), seed_of(7, "scene", 3));
        assert_ne!(seed_of(7, "task", 3), seed_of(8, "task", 3));
    }

    #[test]
    fn below_stays_below_and_covers() {
        let mut r = Rng::new(1);
        let mut seen = [0usize; 5];
        for _ in 0..5000 {
            seen[r.below(5)] += 1;
        }
        assert!(seen.iter().all(|&n| n > 800), "{seen:?}");
    }

    #[test]
    fn weighted_never_draws_a_zero_weight() {
        let mut r = Rng::new(2);
        for _ in 0..1000 {
            assert_ne!(r.weighted(&[1.0, 0.0, 2.0]), 1);
        }
    }
}
