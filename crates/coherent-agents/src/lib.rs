//! `coherent-agents`: the LLM side of COHERENT: the async OpenAI-compatible client,
//! prompt templates, the PEFA loop (Task Assigner, Robot Executors), the baselines,
//! transcripts and the benchmark harness. It talks to any `coherent_core::Environment`;
//! see ARCHITECTURE.md. The loop arrives with the PEFA issue; until then this crate only
//! fixes its place in the workspace.
