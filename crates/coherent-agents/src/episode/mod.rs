mod run;

pub use run::*;
