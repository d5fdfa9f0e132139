//! The bridge's side of DDS: for each robot, the ends of its `Execute` action (the
//! requests and replies of its goal, result and cancel services, and its feedback
//! topic), made on the DDS participant itself rather than through an action client, so
//! that every reply and feedback sample is seen with the participant that wrote it and
//! each reader holds a few samples at most; and the exchange of one step's goals, one
//! per robot acting, all in flight at once (send each, follow its feedback, take its
//! result; cancel it on Ctrl-C or when its robot falls silent) as a blocking call on the
//! runtime the caller hands in (the session's, the one place a runtime is built), which
//! works inside an async runtime as well as outside one. It runs in the link process
//! ([`crate::link_process`]), whose memory limit a flood of DDS samples reaches.
//!
//! A robot is one server, and its server has one client. Two servers for one robot at
//! the start is an error that names them; during an episode, only the server that
//! accepted a goal is heard about it (its result, its feedback as a sign of life), and a
//! second server accepting the same goal stops the bridge, since the robots' world and
//! the rules' would part; so does a reply of a robot's server to another client's goal.

use std::collections::{HashMap, HashSet};
use std::future::Future;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use futures::StreamExt;
use ros2_client::action::{
    CancelGoalResponse, FeedbackMessage, GetResultRequest, GetResultResponse, GoalId, GoalInfo,
    GoalStatusEnum, SendGoalRequest, SendGoalResponse,
};
use ros2_client::builtin_interfaces::Time;
use ros2_client::dds::rustdds::no_key::{DataWriter, SimpleDataReader};
use ros2_client::dds::rustdds::policy::{Durability, History, Reliability, ResourceLimits};
use ros2_client::dds::rustdds::{
    CDRDeserializerAdapter, CDRSerializerAdapter, DomainParticipant,
    DomainParticipantStatusEvent as Event, GUID, Publisher, QosPolicies, QosPolicyBuilder,
    RTPSEntity, SampleIdentity, StatusEvented, Subscriber, Timestamp, Topic, TopicKind,
    WriteOptionsBuilder,
};
use ros2_client::unique_identifier_msgs::UUID;
use tokio::runtime::Handle;
use tokio::time::{Instant, sleep, sleep_until, timeout};

use crate::error::Error;
use crate::wire::{
    self, BefallRequest, BefallResponse, CancelRequest, ExecuteResult, Feedback, Goal,
};

/// How often the wait for the robots' servers looks again.
const RECHECK: Duration = Duration::from_millis(100);
/// How long discovery is given, once every robot has a server, to find a second one.
const SETTLE: Duration = Duration::from_millis(500);
/// How often a goal in flight looks at the cancel flag.
const CANCEL_POLL: Duration = Duration::from_millis(20);
/// How long a cancelled goal waits for the robot's acknowledgement, then its result.
pub(crate) const CANCEL_WAIT: Duration = Duration::from_secs(2);
/// The samples each reader keeps: the replies to one goal and a little feedback. DDS
/// would keep 64 of every topic by default, whatever their size.
const READER_DEPTH: i32 = 4;

type Writer<T> = DataWriter<T, CDRSerializerAdapter<T>>;
type Reader<T> = SimpleDataReader<T, CDRDeserializerAdapter<T>>;

/// How one goal ended, seen from the bridge (and sent from the link process to it, see
/// [`crate::link_process`]).
#[derive(Debug, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Exchange {
    /// The result came, with the goal's end status.
    Result {
        status: GoalStatusEnum,
        result: ExecuteResult,
    },
    /// The server refused the goal.
    Rejected,
    /// Nothing came from the server that accepted the goal for the silence allowed: no
    /// answer to the goal, no feedback, no result; `last` is what was heard last.
    Silent { last: String },
    /// Cancelled (Ctrl-C) before a result came; whether the robot acknowledged it.
    Cancelled { acknowledged: bool },
    /// DDS could not send or receive, or the robot's servers did what one server never
    /// does (two accepted the goal, a result too large to be one).
    Failed(String),
}

impl Exchange {
    /// Whether the robot reports the action carried out (what it observes aside).
    pub(crate) fn succeeded(&self) -> bool {
        matches!(self, Exchange::Result { status, result }
            if *status == GoalStatusEnum::Succeeded && result.success)
    }
}

/// How a request to the world's service ended, seen from the bridge (and sent from the
/// link process to it).
#[derive(Debug, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Befell {
    /// The world's answer.
    Answered(BefallResponse),
    /// No answer within the silence allowed.
    Silent,
    /// DDS could not send or receive, or the answer is larger than one can be.
    Failed(String),
}

/// The bridge's ends of the world's service, made only for a task with events.
struct WorldEnds {
    request: Writer<BefallRequest>,
    replies: Reader<BefallResponse>,
}

/// One robot's ends of its action.
struct Ends {
    goal: Writer<SendGoalRequest<Goal>>,
    goal_replies: Reader<SendGoalResponse>,
    result: Writer<GetResultRequest>,
    result_replies: Reader<GetResultResponse<ExecuteResult>>,
    cancel: Writer<CancelRequest>,
    cancel_replies: Reader<CancelGoalResponse>,
    feedback: Reader<FeedbackMessage<Feedback>>,
}

/// Which remote endpoints each of the bridge's own has been matched with, from the
/// participant's events: what tells that a robot's server is there, and how many.
#[derive(Default)]
struct Matches(HashMap<GUID, HashSet<GUID>>);

impl Matches {
    /// Takes in the events that came since the last look.
    fn update(&mut self, participant: &DomainParticipant) {
        let listener = participant.status_listener();
        while let Some(event) = listener.try_recv_status() {
            match event {
                Event::RemoteReaderMatched {
                    local_writer: local,
                    remote_reader: remote,
                }
                | Event::RemoteWriterMatched {
                    local_reader: local,
                    remote_writer: remote,
                } => {
                    self.0.entry(local).or_default().insert(remote);
                }
                Event::ReaderLost { guid, .. } | Event::WriterLost { guid, .. } => {
                    self.0.values_mut().for_each(|remotes| {
                        remotes.remove(&guid);
                    });
                }
                _ => {}
            }
        }
    }

    fn any(&self, local: GUID) -> bool {
        self.0
            .get(&local)
            .is_some_and(|remotes| !remotes.is_empty())
    }
}

/// The bridge's DDS ends, robot by robot (and the world's, for events), and the runtime
/// to wait on them.
pub(crate) struct Link {
    robots: Vec<Ends>,
    world: Option<WorldEnds>,
    /// The participant, which lives as long as a handle to it does.
    _participant: DomainParticipant,
    runtime: Handle,
}

/// The QoS of the requests the bridge writes, as ROS 2 gives an action's services.
fn request_qos() -> QosPolicies {
    QosPolicyBuilder::new()
        .reliability(Reliability::Reliable {
            max_blocking_time: ros2_client::dds::rustdds::Duration::from_millis(100),
        })
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 })
        .build()
}

/// The QoS of the replies and feedback the bridge reads: reliable and volatile, as the
/// servers offer them, and a few samples kept at most, whatever a participant sends.
fn reader_qos() -> QosPolicies {
    QosPolicyBuilder::new()
        .reliability(Reliability::Reliable {
            max_blocking_time: ros2_client::dds::rustdds::Duration::from_millis(100),
        })
        .durability(Durability::Volatile)
        .history(History::KeepLast {
            depth: READER_DEPTH,
        })
        .resource_limits(ResourceLimits {
            max_samples: READER_DEPTH,
            max_instances: 1,
            max_samples_per_instance: READER_DEPTH,
        })
        .build()
}

/// A DDS failure to make `what`, as the bridge's error.
fn dds<E: std::fmt::Debug>(what: &str) -> impl Fn(E) -> Error + '_ {
    move |e| Error::Dds(format!("{what}: {e:?}"))
}

/// Where the bridge's ends are made: its participant, publisher and subscriber.
struct Maker<'a> {
    participant: &'a DomainParticipant,
    publisher: &'a Publisher,
    subscriber: &'a Subscriber,
}

impl Maker<'_> {
    /// A topic of the participant. A topic's QoS sets how many samples the participant's
    /// cache keeps of it (64 without resource limits), whatever its readers ask for.
    fn topic(&self, name: &str, type_name: &str, qos: &QosPolicies) -> Result<Topic, Error> {
        self.participant
            .create_topic(name.to_owned(), type_name.to_owned(), qos, TopicKind::NoKey)
            .map_err(dds(name))
    }

    /// The writer of the requests of topic `name`, of DDS type `type_name`.
    fn writer<T: serde::Serialize>(&self, name: &str, type_name: &str) -> Result<Writer<T>, Error> {
        let topic = self.topic(name, type_name, &request_qos())?;
        self.publisher
            .create_datawriter_no_key(&topic, Some(request_qos()))
            .map_err(dds(name))
    }

    /// The reader of the replies (or feedback) of topic `name`, of DDS type `type_name`.
    fn reader<T: serde::de::DeserializeOwned + 'static>(
        &self,
        name: &str,
        type_name: &str,
    ) -> Result<Reader<T>, Error> {
        let topic = self.topic(name, type_name, &reader_qos())?;
        self.subscriber
            .create_simple_datareader_no_key(&topic, Some(reader_qos()))
            .map_err(dds(name))
    }
}

impl Ends {
    /// The ends of `robot`'s action under `namespace`.
    fn make(maker: &Maker<'_>, namespace: &str, robot: &str) -> Result<Ends, Error> {
        let names = wire::dds_names(namespace, robot).map_err(Error::Dds)?;
        Ok(Ends {
            goal: maker.writer(&names.goal_request, &names.goal_request_type)?,
            goal_replies: maker.reader(&names.goal_reply, &names.goal_reply_type)?,
            result: maker.writer(&names.result_request, &names.result_request_type)?,
            result_replies: maker.reader(&names.result_reply, &names.result_reply_type)?,
            cancel: maker.writer(&names.cancel_request, &names.cancel_request_type)?,
            cancel_replies: maker.reader(&names.cancel_reply, &names.cancel_reply_type)?,
            feedback: maker.reader(&names.feedback, &names.feedback_type)?,
        })
    }

    /// Whether a server reads each of the robot's requests and writes each of its
    /// replies: the bridge's ends are matched with one.
    fn served(&self, matches: &Matches) -> bool {
        [self.goal.guid(), self.result.guid(), self.cancel.guid()]
            .into_iter()
            .chain([
                self.goal_replies.guid(),
                self.result_replies.guid(),
                self.cancel_replies.guid(),
            ])
            .all(|local| matches.any(local))
    }

    /// The participants (as shown) that write the robot's goal replies: its servers.
    fn servers(&self, matches: &Matches) -> Vec<String> {
        let mut servers: Vec<String> = matches
            .0
            .get(&self.goal_replies.guid())
            .into_iter()
            .flatten()
            .map(|&writer| participant_of(writer))
            .collect();
        servers.sort();
        servers.dedup();
        servers
    }
}

/// A DDS participant as messages name it: `participant` and its GUID prefix in hex.
fn participant_of(guid: GUID) -> String {
    let bytes = guid.to_bytes();
    let hex: String = bytes[..12].iter().map(|b| format!("{b:02x}")).collect();
    format!("participant {hex}")
}

/// Whether `guid` belongs to the participant `prefix` ([`participant_of`]).
fn same_participant(guid: GUID, prefix: &[u8; 12]) -> bool {
    guid.to_bytes()[..12] == prefix[..]
}

fn prefix_of(guid: GUID) -> [u8; 12] {
    let mut prefix = [0; 12];
    prefix.copy_from_slice(&guid.to_bytes()[..12]);
    prefix
}

impl Link {
    /// Joins DDS, makes the ends of each of `robots`' actions under `namespace` (and of
    /// the world's service when the task has `events`), waits up to `wait` for every
    /// robot's server (and the world's) to appear, then a moment more for a second one: a
    /// robot with two servers is an error that names them. Goals are followed on
    /// `runtime`.
    pub(crate) fn connect(
        namespace: &str,
        robots: &[String],
        events: bool,
        wait: Duration,
        runtime: Handle,
    ) -> Result<Link, Error> {
        let context = wire::context().map_err(Error::Dds)?;
        let participant = context.domain_participant();
        let qos = request_qos();
        let publisher = participant
            .create_publisher(&qos)
            .map_err(dds("a publisher"))?;
        let subscriber = participant
            .create_subscriber(&qos)
            .map_err(dds("a subscriber"))?;
        let maker = Maker {
            participant: &participant,
            publisher: &publisher,
            subscriber: &subscriber,
        };
        let ends = robots
            .iter()
            .map(|r| Ends::make(&maker, namespace, r))
            .collect::<Result<Vec<_>, _>>()?;
        let world = if events {
            Some(WorldEnds::make(&maker, namespace)?)
        } else {
            None
        };
        let link = Link {
            robots: ends,
            world,
            _participant: participant.clone(),
            runtime,
        };
        let world_served = |m: &Matches| link.world.as_ref().is_none_or(|w| w.served(m));
        let mut matches = Matches::default();
        let start = std::time::Instant::now();
        loop {
            matches.update(&participant);
            let all = link.robots.iter().all(|e| e.served(&matches)) && world_served(&matches);
            if all || start.elapsed() >= wait {
                break;
            }
            std::thread::sleep(RECHECK);
        }
        let mut missing: Vec<String> = robots
            .iter()
            .zip(&link.robots)
            .filter(|(_, e)| !e.served(&matches))
            .map(|(r, _)| r.clone())
            .collect();
        if !world_served(&matches) {
            missing.push(format!(
                "{} (the service that carries the task's events out)",
                wire::service_name(namespace)
            ));
        }
        if !missing.is_empty() {
            return Err(Error::Missing {
                robots: missing,
                namespace: namespace.to_owned(),
                waited: wait,
            });
        }
        std::thread::sleep(SETTLE);
        matches.update(&participant);
        for (robot, e) in robots.iter().zip(&link.robots) {
            let servers = e.servers(&matches);
            if servers.len() > 1 {
                return Err(Error::Several {
                    robot: robot.clone(),
                    namespace: namespace.to_owned(),
                    servers,
                });
            }
        }
        Ok(link)
    }

    /// Sends each goal to its robot (by number) at once and waits for every one's end:
    /// its result, a refusal, `silence` without a word, or `cancel` raised (then every
    /// goal still in flight is cancelled). One exchange per goal, in the order given; it
    /// takes as long as the slowest robot.
    pub(crate) fn exchange(
        &self,
        goals: Vec<(usize, Goal)>,
        silence: Duration,
        cancel: Option<&AtomicBool>,
    ) -> Vec<Exchange> {
        let each = goals
            .into_iter()
            .map(|(robot, goal)| follow_goal(&self.robots[robot], goal, silence, cancel));
        self.block(futures::future::join_all(each))
    }

    /// Sends `request` to the world's service and waits up to `silence` for its answer.
    pub(crate) fn befall(&self, request: BefallRequest, silence: Duration) -> Befell {
        let Some(world) = &self.world else {
            return Befell::Failed("the link was made for a task without events".into());
        };
        self.block(ask_world(world, request, silence))
    }

    /// Runs `future` to its end on the link's runtime, from a thread of its own, so that
    /// the caller may be inside a runtime (an episode's) or in none.
    fn block<T: Send>(&self, future: impl Future<Output = T> + Send) -> T {
        let handle = &self.runtime;
        std::thread::scope(|s| {
            s.spawn(|| handle.block_on(future))
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
        })
    }
}

impl WorldEnds {
    /// The ends of the world's service under `namespace`.
    fn make(maker: &Maker<'_>, namespace: &str) -> Result<WorldEnds, Error> {
        let [(request, request_type), (reply, reply_type)] =
            wire::service_dds_names(namespace).map_err(Error::Dds)?;
        Ok(WorldEnds {
            request: maker.writer(&request, &request_type)?,
            replies: maker.reader(&reply, &reply_type)?,
        })
    }

    /// Whether a server reads the requests and writes the replies.
    fn served(&self, matches: &Matches) -> bool {
        matches.any(self.request.guid()) && matches.any(self.replies.guid())
    }
}

/// Sends `request` to the world's service and takes the answer to it, within `silence`.
async fn ask_world(world: &WorldEnds, request: BefallRequest, silence: Duration) -> Befell {
    let asked = match send(&world.request, request) {
        Ok(id) => id,
        Err(why) => return Befell::Failed(why),
    };
    let replies = world.replies.as_async_stream();
    tokio::pin!(replies);
    let answer = async {
        loop {
            match replies.next().await {
                Some(Ok(r)) if r.related_sample_identity() == Some(asked) => {
                    return match wire::befall_checked(r.sample) {
                        Ok(response) => Befell::Answered(response),
                        Err(why) => Befell::Failed(why),
                    };
                }
                Some(Ok(_)) => {}
                Some(Err(e)) => return Befell::Failed(format!("cannot read the answer: {e:?}")),
                None => return Befell::Failed("the answers ended".into()),
            }
        }
    };
    timeout(silence, answer).await.unwrap_or(Befell::Silent)
}

/// Resolves once `flag` is raised; never without one.
async fn raised(flag: Option<&AtomicBool>) {
    match flag {
        Some(flag) => {
            while !flag.load(Ordering::SeqCst) {
                sleep(CANCEL_POLL).await;
            }
        }
        None => std::future::pending().await,
    }
}

/// Writes `request` with a source timestamp, as ROS 2's clients do; its identity is what
/// the server's reply names.
fn send<T>(writer: &Writer<T>, request: T) -> Result<SampleIdentity, String>
where
    T: serde::Serialize + std::fmt::Debug,
{
    let options = WriteOptionsBuilder::new()
        .source_timestamp(Timestamp::now())
        .build();
    writer
        .write_with_options(request, options)
        .map_err(|e| format!("cannot send a request: {e:?}"))
}

/// Sends `goal` to the robot of `ends` and follows it to its end: the result of the
/// server that took it, a refusal, `silence` without a word from that server, or
/// `cancel` raised (the goal is then cancelled).
async fn follow_goal(
    ends: &Ends,
    goal: Goal,
    silence: Duration,
    cancel: Option<&AtomicBool>,
) -> Exchange {
    if cancel.is_some_and(|flag| flag.load(Ordering::SeqCst)) {
        return Exchange::Cancelled {
            acknowledged: false,
        };
    }
    let cancelled = raised(cancel);
    tokio::pin!(cancelled);
    let goal_id = UUID::new_random();
    // Sent at once, so that the goal's id is known should it have to be cancelled.
    let request = match send(&ends.goal, SendGoalRequest { goal_id, goal }) {
        Ok(id) => id,
        Err(why) => return Exchange::Failed(why),
    };
    let goal_replies = ends.goal_replies.as_async_stream();
    tokio::pin!(goal_replies);
    // The first answer to this goal names its server; no other is heard about it.
    let (server, accepted) = loop {
        tokio::select! {
            reply = goal_replies.next() => match reply {
                Some(Ok(r)) if r.related_sample_identity() == Some(request) => {
                    break (prefix_of(r.writer_guid()), r.sample.accepted);
                }
                Some(Ok(r)) => {
                    if let Some(why) = other_client(r.related_sample_identity(), request) {
                        let _ = send(&ends.cancel, cancel_request(goal_id));
                        return Exchange::Failed(why);
                    }
                }
                Some(Err(e)) => return Exchange::Failed(format!("cannot read the goal's answer: {e:?}")),
                None => return Exchange::Failed("the goal's answers ended".into()),
            },
            () = sleep(silence) => {
                let _ = send(&ends.cancel, cancel_request(goal_id));
                return Exchange::Silent { last: "nothing: the goal was never answered".into() };
            }
            () = &mut cancelled => return cancel_goal(ends, goal_id, None).await,
        }
    };
    if !accepted {
        return Exchange::Rejected;
    }
    let asked = match send(&ends.result, GetResultRequest { goal_id }) {
        Ok(id) => id,
        Err(why) => return Exchange::Failed(why),
    };
    let results = ends.result_replies.as_async_stream();
    tokio::pin!(results);
    let feedback = ends.feedback.as_async_stream();
    tokio::pin!(feedback);
    let mut last = "the goal's acceptance".to_owned();
    let mut deadline = Instant::now() + silence;
    loop {
        tokio::select! {
            reply = results.next() => match reply {
                Some(Ok(r)) if r.related_sample_identity() == Some(asked)
                    && same_participant(r.writer_guid(), &server) =>
                {
                    let GetResultResponse { status, result } = r.sample;
                    return match wire::checked(result) {
                        Ok(result) => Exchange::Result { status, result },
                        Err(why) => Exchange::Failed(why),
                    };
                }
                Some(Ok(_)) => {}
                Some(Err(e)) => return Exchange::Failed(format!("cannot read the result: {e:?}")),
                None => return Exchange::Failed("the results ended".into()),
            },
            sample = feedback.next() => {
                // A sign of life only from the server that took the goal, about this goal,
                // and in a shape a robot sends.
                if let Some(Ok(f)) = sample
                    && f.sample.goal_id == goal_id
                    && same_participant(f.writer_guid(), &server)
                    && let Some(heard) = wire::feedback_text(&f.sample.feedback)
                {
                    last = heard;
                    deadline = Instant::now() + silence;
                }
            }
            reply = goal_replies.next() => {
                if let Some(Ok(r)) = &reply
                    && let Some(why) = other_client(r.related_sample_identity(), request)
                {
                    let _ = send(&ends.cancel, cancel_request(goal_id));
                    return Exchange::Failed(why);
                }
                if let Some(Ok(r)) = reply
                    && r.related_sample_identity() == Some(request)
                    && !same_participant(r.writer_guid(), &server)
                    && r.sample.accepted
                {
                    let _ = send(&ends.cancel, cancel_request(goal_id));
                    return Exchange::Failed(format!(
                        "two servers accepted the goal, {} and {}: each carries it out, and \
                         the robot's world and the rules' would part",
                        participant_of(GUID::from_bytes(pad(server))),
                        participant_of(r.writer_guid())
                    ));
                }
            }
            () = sleep_until(deadline) => {
                // Best effort: a robot that wakes up should not go on with it.
                let _ = send(&ends.cancel, cancel_request(goal_id));
                return Exchange::Silent { last };
            }
            () = &mut cancelled => return cancel_goal(ends, goal_id, Some((server, asked))).await,
        }
    }
}

/// Why the robot cannot be followed when a reply of its server answers another client:
/// a goal request (`answered`) not from this bridge's writer of them (whose request
/// `ours` is), so that another participant sends this robot goals. Each client's goals
/// change the robots' world, which the rules of the others then no longer follow: two
/// runs of one task in one namespace and domain went on refusing steps until their
/// budgets were spent, none naming the other.
fn other_client(answered: Option<SampleIdentity>, ours: SampleIdentity) -> Option<String> {
    let other = answered.filter(|id| id.writer_guid != ours.writer_guid)?;
    Some(format!(
        "another client, {}, sends goals to this robot's action server: the robots' world \
         changes by its goals too, and this run's rules no longer follow it (one run per \
         robots: another --namespace, or another ROS_DOMAIN_ID)",
        participant_of(other.writer_guid)
    ))
}

/// A participant's GUID prefix as a whole GUID (its entity id zero), to name it.
fn pad(prefix: [u8; 12]) -> [u8; 16] {
    let mut bytes = [0; 16];
    bytes[..12].copy_from_slice(&prefix);
    bytes
}

fn cancel_request(goal_id: GoalId) -> CancelRequest {
    CancelRequest {
        goal_info: GoalInfo {
            goal_id,
            stamp: Time::ZERO,
        },
    }
}

/// Cancels `goal_id` and waits a little for the acknowledgement and, once a server took
/// the goal (`taken`: the server and the identity of the result request), its result;
/// a result other than "cancelled" that comes all the same (the robot finished first,
/// or refused to stop) is the goal's result.
async fn cancel_goal(
    ends: &Ends,
    goal_id: GoalId,
    taken: Option<([u8; 12], SampleIdentity)>,
) -> Exchange {
    let Ok(request) = send(&ends.cancel, cancel_request(goal_id)) else {
        return Exchange::Cancelled {
            acknowledged: false,
        };
    };
    let replies = ends.cancel_replies.as_async_stream();
    tokio::pin!(replies);
    let acknowledgement = async {
        while let Some(reply) = replies.next().await {
            if let Ok(r) = reply
                && r.related_sample_identity() == Some(request)
                && taken.is_none_or(|(server, _)| same_participant(r.writer_guid(), &server))
            {
                return !r.sample.goals_canceling.is_empty();
            }
        }
        false
    };
    let acknowledged = timeout(CANCEL_WAIT, acknowledgement).await.unwrap_or(false);
    let Some((server, asked)) = taken else {
        return Exchange::Cancelled { acknowledged };
    };
    let results = ends.result_replies.as_async_stream();
    tokio::pin!(results);
    let result = async {
        while let Some(reply) = results.next().await {
            if let Ok(r) = reply
                && r.related_sample_identity() == Some(asked)
                && same_participant(r.writer_guid(), &server)
            {
                return Some(r.sample);
            }
        }
        None
    };
    match timeout(CANCEL_WAIT, result).await {
        Ok(Some(GetResultResponse { status, result })) if status != GoalStatusEnum::Canceled => {
            match wire::checked(result) {
                Ok(result) => Exchange::Result { status, result },
                Err(why) => Exchange::Failed(why),
            }
        }
        _ => Exchange::Cancelled { acknowledged },
    }
}
