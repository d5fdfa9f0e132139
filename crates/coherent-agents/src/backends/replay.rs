//! The replay backend: answers every call with the answer recorded in a transcript, with
//! no network, after checking that the call is the one recorded (same role, robot and
//! prompt). Run with the transcript's settings, an episode replays step for step, down
//! to the endpoint each call names.

use std::collections::VecDeque;
use std::sync::{Mutex, PoisonError};

use crate::llm::{
    Answer, Backend, BackendInfo, BackendKind, BoxFuture, LlmError, LlmErrorKind, Query, Response,
};
use crate::records::transcript::{Call, Transcript};

#[derive(Debug)]
pub struct ReplayBackend {
    recorded: BackendInfo,
    calls: Mutex<VecDeque<(u32, Call)>>,
}

impl ReplayBackend {
    pub fn new(transcript: &Transcript) -> ReplayBackend {
        let calls = transcript
            .rounds
            .iter()
            .flat_map(|r| r.calls.iter().map(move |c| (r.step, c.clone())))
            .collect();
        ReplayBackend {
            recorded: transcript.header.backend.clone(),
            calls: Mutex::new(calls),
        }
    }

    /// The recorded call's answer (or error) and the endpoint it names: the next call
    /// recorded, or, when a round asked several roles at once (a parallel round's
    /// executors), the first call of that round for the same role and robot, whichever
    /// of them is asked first.
    fn next(&self, q: &Query) -> Response {
        let mut calls = self.calls.lock().unwrap_or_else(PoisonError::into_inner);
        let robot = q.robot.map(|r| r.0);
        let at = calls.front().and_then(|&(step, _)| {
            calls
                .iter()
                .take_while(|(s, _)| *s == step)
                .position(|(_, c)| c.role == q.role && c.robot == robot)
        });
        let Some((step, call)) = calls.remove(at.unwrap_or(0)) else {
            return Response {
                result: Err(LlmError::new(
                    LlmErrorKind::Replay,
                    "the transcript has no more calls",
                )),
                endpoint: None,
            };
        };
        if let Err(e) = Self::same_call(step, &call, q) {
            return Response {
                result: Err(e),
                endpoint: None,
            };
        }
        let result = match (call.answer, call.error) {
            (Some(answer), _) => Ok(answer),
            (None, Some(error)) => Err(error),
            (None, None) => Err(LlmError::new(
                LlmErrorKind::Replay,
                format!("round {step}: the answer (none recorded) differs from the recorded call"),
            )),
        };
        Response {
            result,
            endpoint: call.endpoint,
        }
    }

    /// Whether `q` is the call recorded in round `step`.
    fn same_call(step: u32, call: &Call, q: &Query) -> Result<(), LlmError> {
        let diverged = |what: &str| {
            LlmError::new(
                LlmErrorKind::Replay,
                format!("round {step}: the {what} differs from the recorded call"),
            )
        };
        if call.role != q.role {
            return Err(diverged("role"));
        }
        if call.robot != q.robot.map(|r| r.0) {
            return Err(diverged("robot"));
        }
        if call.messages != q.messages {
            return Err(diverged("prompt"));
        }
        Ok(())
    }
}

impl Backend for ReplayBackend {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            kind: BackendKind::Replay,
            model: self.recorded.model.clone(),
            base_url: None,
        }
    }

    fn ask(&self, query: Query) -> BoxFuture<'_, Result<Answer, LlmError>> {
        Box::pin(async move { self.next(&query).result })
    }

    fn respond(&self, query: Query) -> BoxFuture<'_, Response> {
        Box::pin(async move { self.next(&query) })
    }
}
