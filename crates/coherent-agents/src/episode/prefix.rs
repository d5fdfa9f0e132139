//! How much of each prompt a server's prefix cache could skip: the characters at the
//! start of a call's messages that are the same as at the start of the previous call of
//! the same role and robot in the episode (`Call::shared_prefix` in the transcript). A
//! server keeps the work done on a prompt's beginning and reuses it for the next prompt
//! that begins the same way; the built-in templates put what never changes first so
//! that this share is large (docs/prompts.md, "Prompt caching").

use std::collections::HashMap;

use crate::llm::{Message, Role};
use crate::records::transcript::Call;

/// The last prompt of each role and robot in an episode.
#[derive(Debug, Default)]
pub(crate) struct LastPrompts {
    last: HashMap<(Role, Option<i64>), Vec<Message>>,
}

impl LastPrompts {
    /// Records in each of `calls`, in order, its shared prefix with the previous call of
    /// its role and robot (none for the first), and remembers its prompt.
    pub(crate) fn mark(&mut self, calls: &mut [Call]) {
        for call in calls {
            let key = (call.role, call.robot);
            call.shared_prefix = self
                .last
                .get(&key)
                .map(|before| shared_prefix(before, &call.messages));
            self.last.insert(key, call.messages.clone());
        }
    }
}

/// The characters that `a` and `b` share from their start: whole messages while both
/// role and text agree, then the common beginning of the first message whose text
/// differs (when the roles agree).
pub fn shared_prefix(a: &[Message], b: &[Message]) -> u64 {
    let mut shared = 0;
    for (x, y) in a.iter().zip(b) {
        if x.role != y.role {
            break;
        }
        let common = x
            .content
            .chars()
            .zip(y.content.chars())
            .take_while(|(p, q)| p == q)
            .count();
        shared += common as u64;
        if x.content != y.content {
            break;
        }
    }
    shared
}

/// The characters of a prompt: its messages' texts.
pub fn prompt_chars(messages: &[Message]) -> u64 {
    messages
        .iter()
        .map(|m| m.content.chars().count() as u64)
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn call(role: Role, robot: Option<i64>, texts: &[&str]) -> Call {
        Call {
            role,
            robot,
            messages: texts
                .iter()
                .enumerate()
                .map(|(i, t)| {
                    if i == 0 {
                        Message::system((*t).to_owned())
                    } else {
                        Message::user((*t).to_owned())
                    }
                })
                .collect(),
            answer: None,
            error: None,
            client: None,
            endpoint: None,
            shared_prefix: None,
        }
    }

    #[test]
    fn the_prefix_is_shared_with_the_last_call_of_the_same_role_and_robot() {
        let mut last = LastPrompts::default();
        let mut first = [
            call(Role::Assigner, None, &["rules", "scene A, then state 1"]),
            call(Role::Executor, Some(7), &["dog", "state 1"]),
        ];
        last.mark(&mut first);
        assert_eq!(first.each_ref().map(|c| c.shared_prefix), [None, None]);
        let mut next = [
            call(Role::Executor, Some(8), &["dog", "state 1"]),
            call(Role::Assigner, None, &["rules", "scene A, then state 2"]),
            call(Role::Executor, Some(7), &["dog", "state 2"]),
            call(Role::Executor, Some(7), &["arm", "state 2"]),
        ];
        last.mark(&mut next);
        // Another robot is a first call; "rules" (5) and "scene A, then state " (20).
        assert_eq!(
            next.each_ref().map(|c| c.shared_prefix),
            [None, Some(25), Some(9), Some(0)]
        );
        assert_eq!(prompt_chars(&next[1].messages), 26);
    }

    #[test]
    fn a_different_role_ends_the_shared_prefix() {
        let a = [Message::system("same".into()), Message::user("x".into())];
        let b = [Message::user("same".into()), Message::user("x".into())];
        assert_eq!(shared_prefix(&a, &b), 0);
        assert_eq!(shared_prefix(&a, &a), 5);
        assert_eq!(shared_prefix(&a, &a[..1]), 4);
    }
}
