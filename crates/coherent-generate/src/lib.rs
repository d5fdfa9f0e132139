//! `coherent-generate`: task sets without end. Scenes are laid out from a catalogue of
//! rooms, furniture and things with real dimensions, on one or two storeys; teams of any
//! mix and size start in them; goals of one to several predicates are drawn with an
//! English instruction; and every task carries the ground truth the engine's own
//! searches prove: its optimal sequential plan, its fewest joint steps (or their bounds
//! where a search limit stops the proof), its type and the fewest robots it needs.
//! Every task is a native task file under the `geometric` rules whose scene the physics
//! builds. The same request and version give the same tasks, byte for byte.
//!
//! [`generate`] makes a set; the session layer writes it out (`coherent generate`,
//! `coherent.generate`).

// Layers, lowest first
pub mod catalogue;
pub mod compose;
mod furnish;
pub mod goal;
pub mod phrase;
pub mod request;
pub mod rng;
pub mod scene;
pub mod set;
pub mod sheet;
pub mod start;
pub mod truth;

pub use request::{KnobError, Ratio, Request, Span, TeamSpec};
pub use set::{Generated, Outcome, Progress, generate};
pub use sheet::{About, Entry, Split, Tally};
