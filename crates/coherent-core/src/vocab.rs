//! The world's vocabulary, named as in docs/semantics.md ("The scene graph"): relations, node properties and
//! node states. Properties and states are bit sets; names the rules do not know are
//! kept per task (see [`Vocabulary`]) so that any file of the original format imports
//! losslessly.

use std::fmt;

/// A directed relation between two nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Relation {
    On = 0,
    Inside = 1,
    LeadingTo = 2,
    With = 3,
    Close = 4,
    Hold = 5,
    Above = 6,
}

impl Relation {
    pub const ALL: [Relation; 7] = [
        Relation::On,
        Relation::Inside,
        Relation::LeadingTo,
        Relation::With,
        Relation::Close,
        Relation::Hold,
        Relation::Above,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Relation::On => "ON",
            Relation::Inside => "INSIDE",
            Relation::LeadingTo => "LEADING TO",
            Relation::With => "WITH",
            Relation::Close => "CLOSE",
            Relation::Hold => "HOLD",
            Relation::Above => "ABOVE",
        }
    }

    pub fn from_name(name: &str) -> Option<Relation> {
        Relation::ALL.into_iter().find(|r| r.name() == name)
    }

    pub(crate) fn from_bits(bits: u32) -> Relation {
        // A match, not a table: edges decode their relation in every inner loop, and
        // this compiles to no lookup and no bounds check.
        match bits {
            0 => Relation::On,
            1 => Relation::Inside,
            2 => Relation::LeadingTo,
            3 => Relation::With,
            4 => Relation::Close,
            5 => Relation::Hold,
            _ => Relation::Above,
        }
    }

    /// ON and INSIDE place a thing somewhere; the goal test counts only these.
    pub fn is_location(self) -> bool {
        matches!(self, Relation::On | Relation::Inside)
    }
}

impl fmt::Display for Relation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

macro_rules! name_table {
    ($(#[$doc:meta])* $set:ident, $word:ty, $known:ident, [$($name:ident),* $(,)?]) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct $set(pub $word);

        #[allow(non_upper_case_globals)]
        impl $set {
            name_table!(@consts $set, 0, $($name),*);
            /// Names the rules know, in bit order.
            pub const $known: &'static [&'static str] = &[$(stringify!($name)),*];

            pub const NONE: $set = $set(0);

            pub fn contains(self, other: $set) -> bool {
                self.0 & other.0 == other.0
            }
            pub fn intersects(self, other: $set) -> bool {
                self.0 & other.0 != 0
            }
            pub fn with(self, other: $set) -> $set {
                $set(self.0 | other.0)
            }
            pub fn without(self, other: $set) -> $set {
                $set(self.0 & !other.0)
            }
            pub fn is_empty(self) -> bool {
                self.0 == 0
            }
            /// The bit of the known name `name`, if the rules know it.
            pub fn known(name: &str) -> Option<$set> {
                Self::$known.iter().position(|n| *n == name).map(|i| $set(1 << i))
            }
            /// Bit indices that are set, lowest first.
            pub fn bits(self) -> impl Iterator<Item = u32> {
                let word = self.0;
                (0..<$word>::BITS).filter(move |b| word >> b & 1 == 1)
            }
        }

        impl std::ops::BitOr for $set {
            type Output = $set;
            fn bitor(self, rhs: $set) -> $set {
                self.with(rhs)
            }
        }

        impl fmt::Debug for $set {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                let mut list = f.debug_set();
                for b in self.bits() {
                    match Self::$known.get(b as usize) {
                        Some(name) => list.entry(name),
                        None => list.entry(&b),
                    };
                }
                list.finish()
            }
        }
    };
    (@consts $set:ident, $i:expr, $name:ident $(, $rest:ident)*) => {
        pub const $name: $set = $set(1 << $i);
        name_table!(@consts $set, $i + 1, $($rest),*);
    };
    (@consts $set:ident, $i:expr,) => {};
}

name_table!(
    /// Node properties (`SURFACES`, `GRABABLE`, ...). Bits past the known names hold a
    /// task's own extra property names, see [`Vocabulary`].
    PropSet,
    u64,
    KNOWN,
    [
        SURFACES,
        LANDABLE,
        LOW_HEIGHT,
        HIGH_HEIGHT,
        ON_HIGH_SURFACE,
        CONTAINERS,
        CAN_OPEN,
        GRABABLE,
        MOVABLE,
        FLYABLE,
        HAVE_A_BASKET,
        WITH_QUADROTOR,
        HEATABLE,
        HAS_SWITCH,
        HAS_PLUG,
    ]
);

name_table!(
    /// Node states (`OPEN`, `CLOSED`, `LAND`, ...). Bits past the known names hold a
    /// task's own extra state names, see [`Vocabulary`].
    StateSet,
    u32,
    KNOWN,
    [OPEN_FOREVER, CLOSED, OPEN, LAND, FLYING, EMPTY, FULL, HOT, COLD, OFF]
);

impl StateSet {
    /// Open for putting things in and for seeing inside.
    pub fn is_open(self) -> bool {
        self.intersects(StateSet::OPEN | StateSet::OPEN_FOREVER)
    }
}

/// Names of properties and states beyond the known ones, in the order a task first used
/// them. They have no meaning to the rules but survive import and export.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Vocabulary {
    pub extra_properties: Vec<String>,
    pub extra_states: Vec<String>,
}

impl Vocabulary {
    pub fn property(&mut self, name: &str) -> Option<PropSet> {
        PropSet::known(name).or_else(|| {
            intern(&mut self.extra_properties, name, PropSet::KNOWN.len(), 64)
                .map(|b| PropSet(1 << b))
        })
    }

    pub fn state(&mut self, name: &str) -> Option<StateSet> {
        StateSet::known(name).or_else(|| {
            intern(&mut self.extra_states, name, StateSet::KNOWN.len(), 32)
                .map(|b| StateSet(1 << b))
        })
    }

    pub fn property_names(&self, set: PropSet) -> Vec<String> {
        names(set.bits(), PropSet::KNOWN, &self.extra_properties)
    }

    pub fn state_names(&self, set: StateSet) -> Vec<String> {
        names(set.bits(), StateSet::KNOWN, &self.extra_states)
    }
}

fn intern(extra: &mut Vec<String>, name: &str, first_bit: usize, bits: usize) -> Option<usize> {
    let pos = match extra.iter().position(|n| n == name) {
        Some(pos) => pos,
        None => {
            extra.push(name.to_owned());
            extra.len() - 1
        }
    };
    (first_bit + pos < bits).then_some(first_bit + pos)
}

fn names(bits: impl Iterator<Item = u32>, known: &[&str], extra: &[String]) -> Vec<String> {
    bits.map(|b| {
        let b = b as usize;
        known
            .get(b)
            .map(|s| (*s).to_owned())
            .unwrap_or_else(|| extra[b - known.len()].clone())
    })
    .collect()
}
