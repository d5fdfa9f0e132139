//! The interface on the wire, as the ROS 2 package `ros/coherent_msgs` defines it: one
//! action `coherent_msgs/action/Execute` per robot, at `/<namespace>/<robot>/execute`.
//!
//! The structs mirror `Execute.action` and `Relation.msg` field by field, in order: CDR,
//! the encoding ROS 2 uses on DDS, writes fields in declaration order by type, so these
//! serde structs are the same bytes as the C++ and Python types colcon generates. The
//! names of robots and actions, the DDS context (`ROS_DOMAIN_ID`) and the QoS profiles
//! ROS 2 gives actions are here too, so that the bridge and the servers agree on them.

use ros2_client::action::{ActionClientQosPolicies, ActionServerQosPolicies};
use ros2_client::qos::{Durability, History};
use ros2_client::{ActionTypeName, Context, ContextOptions, Message, Name, QosProfile};
use serde::{Deserialize, Serialize};

use coherent_core::{Idx, Task};

use crate::error::Error;

/// The package of the interface.
pub const PACKAGE: &str = "coherent_msgs";
/// The action type, `coherent_msgs/action/Execute`.
pub const ACTION_TYPE: &str = "Execute";
/// The last token of every robot's action name.
pub const ACTION_BASE: &str = "execute";
/// Where the robots' actions live unless a namespace is given.
pub const DEFAULT_NAMESPACE: &str = "/coherent";

/// Feedback stage: the goal is accepted and the robot starts.
pub const STAGE_STARTED: &str = "started";
/// Feedback stage: the robot is carrying the action out.
pub const STAGE_WORKING: &str = "working";
/// Feedback stage: the robot is done and the result follows.
pub const STAGE_FINISHED: &str = "finished";

/// `Execute.action`'s goal: one action of the project's grammar, e.g.
/// `[grab] <apple>(9)`, and the count of the actions tried in the episode, this one
/// included (1 first).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Goal {
    pub action: String,
    pub step: u32,
}

/// `Execute.action`'s feedback: what the robot is at, and how far, 0 to 1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Feedback {
    pub stage: String,
    pub progress: f32,
}

/// `Execute.action`'s result: whether the action was carried out; if not, a category
/// (a feasibility reason name of the project such as `not_close`, `physics`, or `robot`
/// for anything else) and, always, a message in words; then the relations the robot
/// observes after acting (may be empty).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ExecuteResult {
    pub success: bool,
    pub reason: String,
    pub message: String,
    pub relations: Vec<Relation>,
}

/// `coherent_msgs/msg/Relation`: `subject relation object` in the task's own words, e.g.
/// `<apple>(9) INSIDE <fridge>(3)`; the relation is one of the task graph's (`ON`,
/// `INSIDE`, `CLOSE`, `HOLD`, `ABOVE`), or [`IS`] with a state as the object
/// (`<fridge>(3) IS OPEN`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Relation {
    pub subject: String,
    pub relation: String,
    pub object: String,
}

/// The relation word for a node's state.
pub const IS: &str = "IS";

impl Message for Goal {}
impl Message for Feedback {}
impl Message for ExecuteResult {}
impl Message for Relation {}

/// `coherent_msgs/action/Execute`.
pub(crate) fn action_type() -> ActionTypeName {
    ActionTypeName::new(PACKAGE, ACTION_TYPE)
}

/// The ROS name of robot `robot`: its class name in lower case, anything but letters
/// and digits as `_`, then its id (a minus sign as `m`); `<robot dog>(13)` is
/// `robot_dog_13`.
pub fn robot_name(task: &Task, robot: Idx) -> String {
    let node = task.node(robot);
    let mut name = String::new();
    for c in node.class_name.chars() {
        if c.is_ascii_alphanumeric() {
            name.push(c.to_ascii_lowercase());
        } else if !name.is_empty() && !name.ends_with('_') {
            name.push('_');
        }
    }
    if name.is_empty() || name.starts_with(|c: char| c.is_ascii_digit()) {
        name.insert_str(0, "robot_");
    }
    if !name.ends_with('_') {
        name.push('_');
    }
    name.push_str(&node.id.0.to_string().replace('-', "m"));
    name
}

/// The ROS names of a task's robots, in the task's order.
pub fn robot_names(task: &Task) -> Vec<String> {
    task.robots
        .iter()
        .map(|r| robot_name(task, r.node))
        .collect()
}

/// A namespace as given (`coherent`, `/coherent`, `/lab/bench_2/`) in its absolute form
/// without a trailing slash; every token must be a ROS name token (a letter or `_`,
/// then letters, digits and `_`).
pub fn namespace(given: &str) -> Result<String, Error> {
    let tokens: Vec<&str> = given.split('/').filter(|t| !t.is_empty()).collect();
    let valid = |t: &str| {
        t.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
            && t.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
    };
    if tokens.is_empty() || !tokens.iter().all(|t| valid(t)) {
        return Err(Error::Invalid(format!(
            "{given:?} is not a ROS namespace (tokens of letters, digits and _, each \
             starting with a letter or _, separated by /)"
        )));
    }
    Ok(format!("/{}", tokens.join("/")))
}

/// The action of `robot` under `namespace` (absolute), `/<namespace>/<robot>/execute`.
pub fn action_name(namespace: &str, robot: &str) -> String {
    format!("{namespace}/{robot}/{ACTION_BASE}")
}

/// [`action_name`] as ros2-client takes it.
pub(crate) fn ros_action_name(namespace: &str, robot: &str) -> Result<Name, String> {
    Name::new(&format!("{namespace}/{robot}"), ACTION_BASE)
        .map_err(|e| format!("{}: {e:?}", action_name(namespace, robot)))
}

/// A DDS participant in the domain `ROS_DOMAIN_ID` names (0 when unset), as every ROS 2
/// program joins one.
pub(crate) fn context() -> Result<Context, String> {
    let domain = match std::env::var("ROS_DOMAIN_ID") {
        Ok(v) if !v.trim().is_empty() => v
            .trim()
            .parse::<u16>()
            .map_err(|_| format!("ROS_DOMAIN_ID={v:?} is not a domain id"))?,
        _ => 0,
    };
    Context::with_options(ContextOptions::new().domain_id(domain))
        .map_err(|e| format!("cannot join DDS domain {domain}: {e:?}"))
}

/// ROS 2's profiles for actions: the services (goal, result, cancel) reliable and
/// volatile with a depth of 10, feedback likewise, the status topic transient-local
/// with a depth of 1, so that late joiners see the goals' states.
fn services() -> QosProfile {
    QosProfile::publisher_default()
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 })
}

fn status() -> QosProfile {
    QosProfile::publisher_default()
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth: 1 })
}

pub(crate) fn server_qos() -> ActionServerQosPolicies {
    ActionServerQosPolicies {
        goal_service: services(),
        result_service: services(),
        cancel_service: services(),
        feedback_publisher: services(),
        status_publisher: status(),
    }
}

/// A volatile status subscription matches the servers' transient-local status writer.
pub(crate) fn client_qos() -> ActionClientQosPolicies {
    ActionClientQosPolicies {
        goal_service: services(),
        result_service: services(),
        cancel_service: services(),
        feedback_subscription: services(),
        status_subscription: services(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn namespaces_are_absolute_and_checked() {
        assert_eq!(namespace("coherent").as_deref(), Ok("/coherent"));
        assert_eq!(namespace("/lab/bench_2/").as_deref(), Ok("/lab/bench_2"));
        assert!(namespace("").is_err());
        assert!(namespace("/").is_err());
        assert!(namespace("/2lab").is_err());
        assert!(namespace("/lab-a").is_err());
        assert_eq!(
            action_name("/lab", "robot_dog_13"),
            "/lab/robot_dog_13/execute"
        );
    }
}
