"""A DDS participant that is not RustDDS (Eclipse Cyclone DDS, PyPI `cyclonedds`) reading
the ROS 2 traffic of the robots' actions by its ROS 2 names and types.

    python ros_listener.py NAMESPACE ROBOT...

For each robot it reads `rt/<namespace>/<robot>/execute/_action/feedback`
(`coherent_msgs/action/Execute_FeedbackMessage`) and `.../_action/status`
(`action_msgs/msg/GoalStatusArray`), prints `ready` once its readers exist, and, when its
stdin closes, one JSON object: per robot, the feedback samples and the goal statuses seen.
test_ros_interop.py runs it inside the network namespace of a robots server and a run.
"""

# No `from __future__ import annotations`: cyclonedds reads the field types at run time.
import json
import select
import sys
from dataclasses import dataclass

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, float32, int8, int32, sequence, uint8, uint32
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

# The ROS 2 types as ROS 2 puts them on DDS: `pkg/msg/Name` is `pkg::msg::dds_::Name_`.


@dataclass
class UUID(IdlStruct, typename="unique_identifier_msgs::msg::dds_::UUID_"):
    uuid: array[uint8, 16]


@dataclass
class ExecuteFeedback(IdlStruct, typename="coherent_msgs::action::dds_::Execute_Feedback_"):
    stage: str
    progress: float32


@dataclass
class ExecuteFeedbackMessage(IdlStruct, typename="coherent_msgs::action::dds_::Execute_FeedbackMessage_"):
    goal_id: UUID
    feedback: ExecuteFeedback


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class GoalInfo(IdlStruct, typename="action_msgs::msg::dds_::GoalInfo_"):
    goal_id: UUID
    stamp: Time


@dataclass
class GoalStatus(IdlStruct, typename="action_msgs::msg::dds_::GoalStatus_"):
    goal_info: GoalInfo
    status: int8


@dataclass
class GoalStatusArray(IdlStruct, typename="action_msgs::msg::dds_::GoalStatusArray_"):
    status_list: sequence[GoalStatus]


def main() -> None:
    namespace, robots = sys.argv[1].rstrip("/"), sys.argv[2:]
    participant = DomainParticipant(0)
    # As ROS 2 offers them: feedback reliable and volatile, the status transient-local.
    feedback_qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepAll)
    status_qos = Qos(
        Policy.Reliability.Reliable(duration(seconds=1)),
        Policy.Durability.TransientLocal,
        Policy.History.KeepAll,
    )
    readers = {}
    for robot in robots:
        base = f"rt{namespace}/{robot}/execute/_action"
        feedback = Topic(participant, f"{base}/feedback", ExecuteFeedbackMessage)
        status = Topic(participant, f"{base}/status", GoalStatusArray)
        readers[robot] = (
            DataReader(participant, feedback, qos=feedback_qos),
            DataReader(participant, status, qos=status_qos),
        )
    print("ready", flush=True)
    seen: dict[str, dict[str, list]] = {robot: {"feedback": [], "status": []} for robot in robots}

    def drain() -> None:
        for robot, (feedback, status) in readers.items():
            for sample in feedback.take(N=1000):
                seen[robot]["feedback"].append(
                    {
                        "goal": bytes(sample.goal_id.uuid).hex(),
                        "stage": sample.feedback.stage,
                        "progress": sample.feedback.progress,
                    }
                )
            for sample in status.take(N=1000):
                seen[robot]["status"].extend(
                    {"goal": bytes(s.goal_info.goal_id.uuid).hex(), "status": s.status} for s in sample.status_list
                )

    while True:
        drain()
        readable, _, _ = select.select([sys.stdin], [], [], 0.05)
        if readable and not sys.stdin.read(1):
            break
    drain()
    print(json.dumps(seen), flush=True)


if __name__ == "__main__":
    main()
