"""A third DDS participant (Eclipse Cyclone DDS, PyPI `cyclonedds`) that meddles with a
robot's action: it reads the goals sent to the robot and, every 0.1 s, publishes
feedback for the last one as if it were the robot, a false sign of life. With `--flood
BYTES` it publishes, as fast as it can, feedback whose stage is BYTES long: each such
sample reaches a reader as thousands of DATAFRAG submessages that the reader's DDS
reassembles before anything can look at the stage.

    python ros_intruder.py NAMESPACE ROBOT [--flood BYTES]

It prints `ready` once its reader and writer exist, and, when its stdin closes, one JSON
object: the goals it saw and the feedback samples it sent. test_ros_interop.py runs it
inside the network namespace of a robots server and a run.
"""

# No `from __future__ import annotations`: cyclonedds reads the field types at run time.
import json
import select
import sys
from dataclasses import dataclass

from cyclonedds.core import DDSException, Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, float32, uint8, uint32
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration


@dataclass
class UUID(IdlStruct, typename="unique_identifier_msgs::msg::dds_::UUID_"):
    uuid: array[uint8, 16]


@dataclass
class ExecuteGoal(IdlStruct, typename="coherent_msgs::action::dds_::Execute_Goal_"):
    action: str
    step: uint32


@dataclass
class SendGoalRequest(IdlStruct, typename="coherent_msgs::action::dds_::Execute_SendGoal_Request_"):
    goal_id: UUID
    goal: ExecuteGoal


@dataclass
class ExecuteFeedback(IdlStruct, typename="coherent_msgs::action::dds_::Execute_Feedback_"):
    stage: str
    progress: float32


@dataclass
class ExecuteFeedbackMessage(IdlStruct, typename="coherent_msgs::action::dds_::Execute_FeedbackMessage_"):
    goal_id: UUID
    feedback: ExecuteFeedback


def main() -> None:
    namespace, robot = sys.argv[1].rstrip("/"), sys.argv[2]
    flood = int(sys.argv[4]) if sys.argv[3:4] == ["--flood"] else 0
    stage = "w" * flood if flood else "working"
    participant = DomainParticipant(0)
    reliable = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(10))
    base = f"{namespace}/{robot}/execute/_action"
    goals = DataReader(participant, Topic(participant, f"rq{base}/send_goalRequest", SendGoalRequest), qos=reliable)
    # A flood keeps one sample for resending, not ten: its own memory stays a few samples.
    sending = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(1)) if flood else reliable
    feedback = DataWriter(participant, Topic(participant, f"rt{base}/feedback", ExecuteFeedbackMessage), qos=sending)
    print("ready", flush=True)
    seen: list[UUID] = []
    sent = 0
    while True:
        for request in goals.take(N=100):
            if isinstance(request, SendGoalRequest):  # not a writer's departure
                seen.append(request.goal_id)
        for goal_id in seen[-1:]:
            try:
                feedback.write(ExecuteFeedbackMessage(goal_id, ExecuteFeedback(stage, 0.5)))
                sent += 1
            except DDSException:  # a reliable write that timed out on a reader that lags
                pass
        readable, _, _ = select.select([sys.stdin], [], [], 0 if flood and seen else 0.1)
        if readable and not sys.stdin.read(1):
            break
    print(json.dumps({"goals": len(seen), "sent": sent}), flush=True)


if __name__ == "__main__":
    main()
