//! Asking a backend one question: the call is recorded in the round whatever comes of
//! it, and the answer's text comes back unless it gives nothing to act on (empty,
//! refused, filtered, or the backend failed).

use futures_util::future::join_all;

use crate::episode::cancel::Cancel;
use crate::llm::{Backend, Finish, LlmError, Query};
use crate::records::transcript::{Call, RoundOutcome};

/// Why a role's answer gave nothing to act on.
pub(crate) enum Unusable {
    /// The backend failed for good.
    Failed(LlmError),
    /// An answer came, but not one that can be used.
    Bad(String),
}

/// Which side of a round an unusable answer came from: the one that proposes (PEFA's
/// task assigner) or the one that decides on an action (an executor, a central model, a
/// speaker).
#[derive(Clone, Copy)]
pub(crate) enum Side {
    Assigner,
    Executor,
}

impl Unusable {
    pub(crate) fn outcome(self, side: Side) -> RoundOutcome {
        match (self, side) {
            (Unusable::Failed(e), _) => RoundOutcome::BackendError {
                message: e.to_string(),
            },
            (Unusable::Bad(why), Side::Assigner) => RoundOutcome::NoProposal { why },
            (Unusable::Bad(why), Side::Executor) => RoundOutcome::NoDecision { why },
        }
    }
}

/// An answer's text, and whether generation was cut at the token limit.
pub(crate) struct Reply {
    pub(crate) text: String,
    truncated: bool,
}

impl Reply {
    /// Parses the text; a truncated answer counts when what matters came before the cut
    /// (a small model may pad a complete action with whitespace up to the limit).
    pub(crate) fn read<T>(
        self,
        parse: impl FnOnce(&str) -> Result<T, String>,
    ) -> Result<T, Unusable> {
        parse(&self.text).map_err(|why| {
            Unusable::Bad(if self.truncated {
                format!(
                    "the answer was cut off at the token limit ({why}): {:?}",
                    excerpt(&self.text)
                )
            } else {
                why
            })
        })
    }
}

/// Asks `backend` and records the call: what was asked, its answer or its error, and
/// the endpoint that gave it; `None` when cancelled.
pub(crate) async fn place_call(
    backend: &dyn Backend,
    query: Query,
    cancel: &Cancel,
) -> Option<Call> {
    let mut call = Call {
        role: query.role,
        robot: query.robot.map(|r| r.0),
        messages: query.messages.clone(),
        answer: None,
        error: None,
        client: None,
        endpoint: None,
        shared_prefix: None,
    };
    let response = tokio::select! {
        biased;
        () = cancel.cancelled() => return None,
        r = backend.respond(query) => r,
    };
    call.endpoint = response.endpoint;
    match response.result {
        Ok(answer) => call.answer = Some(answer),
        Err(e) => call.error = Some(e),
    }
    Some(call)
}

/// Asks `backend`, records the call, and gives the answer's text unless it is empty,
/// refused or filtered; `None` when cancelled.
pub(crate) async fn ask(
    backend: &dyn Backend,
    query: Query,
    cancel: &Cancel,
    calls: &mut Vec<Call>,
) -> Option<Result<Reply, Unusable>> {
    let call = place_call(backend, query, cancel).await?;
    let reply = match (&call.answer, &call.error) {
        (Some(answer), _) => match &answer.finish {
            Finish::Refusal(words) => Err(format!("the model refused: {words}")),
            Finish::ContentFilter => Err("the answer was withheld by a content filter".into()),
            _ if answer.text.trim().is_empty() => Err(if answer.finish == Finish::Length {
                "the answer was cut off at the token limit before any text".into()
            } else {
                "the answer was empty".into()
            }),
            finish => Ok(Reply {
                text: answer.text.clone(),
                truncated: *finish == Finish::Length,
            }),
        }
        .map_err(Unusable::Bad),
        (None, Some(e)) if e.ends_episode() => Err(Unusable::Failed(e.clone())),
        (None, Some(e)) => Err(Unusable::Bad(e.to_string())),
        // A call placed records one or the other; a call read back may have neither.
        (None, None) => Err(Unusable::Bad(
            "the call has neither an answer nor an error".into(),
        )),
    };
    calls.push(call);
    Some(reply)
}

/// Asks `backend` every one of `queries` at once (a parallel round's executors, one per
/// robot), so that their calls are in flight together, and waits for all: each reply
/// with the calls it made, in the order of `queries` whatever order they were answered
/// in; `None` when cancelled.
pub(crate) async fn ask_all(
    backend: &dyn Backend,
    queries: Vec<Query>,
    cancel: &Cancel,
) -> Option<Vec<(Vec<Call>, Result<Reply, Unusable>)>> {
    let asks = queries.into_iter().map(|query| async move {
        let mut calls = Vec::new();
        let reply = ask(backend, query, cancel, &mut calls).await;
        reply.map(|r| (calls, r))
    });
    join_all(asks).await.into_iter().collect()
}

fn excerpt(text: &str) -> String {
    let mut s: String = text.chars().take(120).collect();
    if s.len() < text.len() {
        s.push('…');
    }
    s
}
