pub mod builtin;
pub mod llm;
pub mod openai;
pub mod replay;
pub mod retry;
