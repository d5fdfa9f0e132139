pub mod answer;
pub mod cmrs;
pub mod dmrs;
pub mod joint;
pub mod mcts;
pub mod optimal;
pub mod pefa;
pub mod prompt;
