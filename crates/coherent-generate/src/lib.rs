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

// Layers, lowest first: each module names only those above it (scripts/check-layout holds
// the crate to it). The comment above each also keeps rustfmt from sorting them.
// A random stream per draw.
pub mod rng;
// The knobs, and the error that names one.
pub mod request;
// Rooms, furniture and things with their dimensions.
pub mod catalogue;
// The manifest line and the datasheet's counts.
pub mod sheet;
// A scene laid out and furnished.
pub mod scene;
// A team, and where it and the things start.
pub mod start;
// Goal predicates, drawn by the robot kinds they need.
pub mod goal;
// The English instruction.
pub mod phrase;
// The native task file.
pub mod compose;
// The ground truth from the planner's searches.
pub mod truth;
// The driver: draws, threads, filters, order.
pub mod set;
// A task's dynamic variants: one event each, along its optimal plan.
pub mod variants;

pub use request::{KnobError, Ratio, Request, Span, TeamSpec};
pub use set::{Generated, Outcome, Progress, generate, splits};
pub use sheet::{About, Entry, Split, Tally};
