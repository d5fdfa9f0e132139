//! `coherent-sim`: Rapier grounding of the COHERENT world (quadrotors, legged robots,
//! fixed arms). It depends on `coherent-core` only and implements its `Environment`
//! physically; see ARCHITECTURE.md. The physics arrives with the physics issue; until
//! then this crate only fixes its place in the workspace.
