//! The interface on the wire, as the ROS 2 package `ros/coherent_msgs` defines it: one
//! action `coherent_msgs/action/Execute` per robot, at `/<namespace>/<robot>/execute`.
//!
//! The structs mirror `Execute.action` and `Relation.msg` field by field, in order: CDR,
//! the encoding ROS 2 uses on DDS, writes fields in declaration order by type, so these
//! serde structs are the same bytes as the C++ and Python types colcon generates. The
//! names of robots and actions, the DDS context (`ROS_DOMAIN_ID`) and the QoS profiles
//! ROS 2 gives actions are here too, so that the bridge and the servers agree on them.

use ros2_client::action::ActionServerQosPolicies;
use ros2_client::qos::{Durability, History};
use ros2_client::{
    ActionTypeName, Context, ContextOptions, Message, Name, QosProfile, ServiceTypeName,
};
use serde::{Deserialize, Serialize};

use coherent_core::{Idx, Task};

use crate::error::Error;

/// The package of the interface.
pub const PACKAGE: &str = "coherent_msgs";
/// The action type, `coherent_msgs/action/Execute`.
pub const ACTION_TYPE: &str = "Execute";
/// The last token of every robot's action name.
pub const ACTION_BASE: &str = "execute";
/// The world's service type, `coherent_msgs/srv/Befall`.
pub const SERVICE_TYPE: &str = "Befall";
/// The last token of the world's service name, `/<namespace>/befall`.
pub const SERVICE_BASE: &str = "befall";
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

/// `action_msgs/srv/CancelGoal`'s request, as the bridge writes it (ros2-client's own
/// type cannot be made outside its action client): the goal and a time stamp, zero for
/// that goal alone.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(crate) struct CancelRequest {
    pub goal_info: ros2_client::action::GoalInfo,
}

/// `Befall.srv`'s request: what events changed in the robots' world before the action
/// numbered `step`. The team as it now is (robots' ROS names), the doors now locked (as
/// the task names them), and each thing moved with where it now is (`ON` or `INSIDE`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct BefallRequest {
    pub step: u32,
    pub team: Vec<String>,
    pub locked: Vec<String>,
    pub moved: Vec<Relation>,
}

/// `Befall.srv`'s response: whether the world now is as asked, what was done or why not,
/// and where each thing moved now is as the world observes it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct BefallResponse {
    pub accepted: bool,
    pub message: String,
    pub relations: Vec<Relation>,
}

impl Message for Goal {}
impl Message for BefallRequest {}
impl Message for BefallResponse {}
impl Message for Feedback {}
impl Message for ExecuteResult {}
impl Message for Relation {}

/// `coherent_msgs/action/Execute`.
pub(crate) fn action_type() -> ActionTypeName {
    ActionTypeName::new(PACKAGE, ACTION_TYPE)
}

/// `coherent_msgs/srv/Befall`.
pub(crate) fn service_type() -> ServiceTypeName {
    ServiceTypeName::new(PACKAGE, SERVICE_TYPE)
}

/// The world's service under `namespace` (absolute), `/<namespace>/befall`.
pub fn service_name(namespace: &str) -> String {
    format!("{namespace}/{SERVICE_BASE}")
}

/// [`service_name`] as ros2-client takes it.
pub(crate) fn ros_service_name(namespace: &str) -> Result<Name, String> {
    Name::new(namespace, SERVICE_BASE).map_err(|e| format!("{}: {e:?}", service_name(namespace)))
}

/// The DDS topics of the world's service under `namespace` (absolute) and their types,
/// as ROS 2 names a service's: `rq/<service>Request` and `rr/<service>Reply`.
pub(crate) fn service_dds_names(namespace: &str) -> Result<[(String, String); 2], String> {
    ros_service_name(namespace)?;
    let base = service_name(namespace);
    let types = format!("{PACKAGE}::srv::dds_::{SERVICE_TYPE}");
    Ok([
        (format!("rq{base}Request"), format!("{types}_Request_")),
        (format!("rr{base}Reply"), format!("{types}_Response_")),
    ])
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
pub(crate) fn services() -> QosProfile {
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

/// The DDS topics of one robot's action and their types, as ROS 2 names them: an
/// action's services are `rq/<action>/_action/<service>Request` and
/// `rr/.../<service>Reply`, its feedback `rt/<action>/_action/feedback`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct DdsNames {
    pub goal_request: String,
    pub goal_request_type: String,
    pub goal_reply: String,
    pub goal_reply_type: String,
    pub result_request: String,
    pub result_request_type: String,
    pub result_reply: String,
    pub result_reply_type: String,
    pub cancel_request: String,
    pub cancel_request_type: String,
    pub cancel_reply: String,
    pub cancel_reply_type: String,
    pub feedback: String,
    pub feedback_type: String,
}

/// The DDS topics of `robot`'s action under `namespace` (absolute).
pub(crate) fn dds_names(namespace: &str, robot: &str) -> Result<DdsNames, String> {
    // Checked as ROS checks a name, though built by hand below.
    ros_action_name(namespace, robot)?;
    let base = format!("{}/_action", action_name(namespace, robot));
    let action = format!("{PACKAGE}::action::dds_::{ACTION_TYPE}");
    let cancel = "action_msgs::srv::dds_::CancelGoal";
    Ok(DdsNames {
        goal_request: format!("rq{base}/send_goalRequest"),
        goal_request_type: format!("{action}_SendGoal_Request_"),
        goal_reply: format!("rr{base}/send_goalReply"),
        goal_reply_type: format!("{action}_SendGoal_Response_"),
        result_request: format!("rq{base}/get_resultRequest"),
        result_request_type: format!("{action}_GetResult_Request_"),
        result_reply: format!("rr{base}/get_resultReply"),
        result_reply_type: format!("{action}_GetResult_Response_"),
        cancel_request: format!("rq{base}/cancel_goalRequest"),
        cancel_request_type: format!("{cancel}_Request_"),
        cancel_reply: format!("rr{base}/cancel_goalReply"),
        cancel_reply_type: format!("{cancel}_Response_"),
        feedback: format!("rt{base}/feedback"),
        feedback_type: format!("{action}_FeedbackMessage_"),
    })
}

/// The most bytes of a result's message the bridge keeps.
pub const MAX_MESSAGE_BYTES: usize = 4096;
/// The most bytes of a result's reason, of a feedback's stage, and of each part of a
/// relation.
pub const MAX_WORD_BYTES: usize = 256;
/// The most relations a result may list: a robot observes a few dozen.
pub const MAX_RELATIONS: usize = 4096;

/// A result as the bridge keeps it: its message cut at [`MAX_MESSAGE_BYTES`], or an error
/// when it is larger than a robot's result can be (a reason or a relation's word of more
/// than [`MAX_WORD_BYTES`], more than [`MAX_RELATIONS`] relations).
pub(crate) fn checked(mut result: ExecuteResult) -> Result<ExecuteResult, String> {
    if result.reason.len() > MAX_WORD_BYTES {
        return Err(format!(
            "the robot's result is malformed: its reason has {} bytes (at most {MAX_WORD_BYTES})",
            result.reason.len()
        ));
    }
    relations_checked("the robot's result", &result.relations)?;
    result.message = coherent_core::text::cut(&result.message, MAX_MESSAGE_BYTES).into_owned();
    Ok(result)
}

/// `response` as the bridge keeps it, like a robot's result ([`checked`]).
pub(crate) fn befall_checked(mut response: BefallResponse) -> Result<BefallResponse, String> {
    relations_checked("the world's answer", &response.relations)?;
    response.message = coherent_core::text::cut(&response.message, MAX_MESSAGE_BYTES).into_owned();
    Ok(response)
}

/// An error naming `whose` when `relations` are more than [`MAX_RELATIONS`] or hold a
/// word longer than [`MAX_WORD_BYTES`].
pub(crate) fn relations_checked(whose: &str, relations: &[Relation]) -> Result<(), String> {
    if relations.len() > MAX_RELATIONS {
        return Err(format!(
            "{whose} is malformed: it lists {} relations (at most {MAX_RELATIONS})",
            relations.len()
        ));
    }
    for r in relations {
        for word in [&r.subject, &r.relation, &r.object] {
            if word.len() > MAX_WORD_BYTES {
                return Err(format!(
                    "{whose} is malformed: its relation has {} bytes (at most {MAX_WORD_BYTES})",
                    word.len()
                ));
            }
        }
    }
    Ok(())
}

/// What a feedback sample says, as the bridge reports it last heard, or `None` for one
/// no robot sends (a stage longer than [`MAX_WORD_BYTES`], a progress that is no number).
pub(crate) fn feedback_text(f: &Feedback) -> Option<String> {
    (f.stage.len() <= MAX_WORD_BYTES && f.progress.is_finite()).then(|| {
        format!(
            "feedback \"{}\" at {:.0}%",
            coherent_core::text::shown(&f.stage),
            f.progress * 100.0
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dds_names_are_ros2s() {
        let names = dds_names("/lab", "robot_arm_6").expect("valid");
        assert_eq!(
            names.goal_request,
            "rq/lab/robot_arm_6/execute/_action/send_goalRequest"
        );
        assert_eq!(
            names.result_reply,
            "rr/lab/robot_arm_6/execute/_action/get_resultReply"
        );
        assert_eq!(
            names.feedback,
            "rt/lab/robot_arm_6/execute/_action/feedback"
        );
        assert_eq!(
            names.goal_reply_type,
            "coherent_msgs::action::dds_::Execute_SendGoal_Response_"
        );
        assert_eq!(
            names.cancel_request_type,
            "action_msgs::srv::dds_::CancelGoal_Request_"
        );
    }

    #[test]
    fn results_and_feedback_are_capped() {
        let relation = |word: &str| Relation {
            subject: word.into(),
            relation: "ON".into(),
            object: "<table>(3)".into(),
        };
        let result = ExecuteResult {
            success: true,
            reason: String::new(),
            message: "m".repeat(10 << 20),
            relations: vec![relation("<mug>(7)")],
        };
        let kept = checked(result.clone()).expect("a result");
        assert!(kept.message.len() < MAX_MESSAGE_BYTES + 64);
        assert!(kept.message.ends_with("[cut: 10485760 bytes in all]"));
        let many = ExecuteResult {
            relations: vec![relation("<mug>(7)"); MAX_RELATIONS + 1],
            ..result.clone()
        };
        assert!(
            checked(many)
                .expect_err("too many")
                .contains("4097 relations")
        );
        let long = ExecuteResult {
            relations: vec![relation(&"x".repeat(10 << 20))],
            ..result
        };
        assert!(
            checked(long)
                .expect_err("too long")
                .contains("relation has 10485760 bytes")
        );
        let feedback = |stage: &str, progress: f32| Feedback {
            stage: stage.into(),
            progress,
        };
        assert_eq!(
            feedback_text(&feedback("working", 0.5)).as_deref(),
            Some("feedback \"working\" at 50%")
        );
        assert_eq!(feedback_text(&feedback(&"x".repeat(10 << 20), 0.5)), None);
        assert_eq!(feedback_text(&feedback("working", f32::NAN)), None);
        assert_eq!(
            feedback_text(&feedback("\u{1b}[2J", 1.0)).as_deref(),
            Some("feedback \"\\u{1b}[2J\" at 100%")
        );
    }

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
