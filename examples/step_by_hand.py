# %% [markdown]
# # Stepping a COHERENT environment by hand
#
# A notebook as a script: each `# %%` is a cell (VS Code, PyCharm and Jupytext run
# them one by one), and `python examples/step_by_hand.py` runs them all. We load the
# demo task, look at what the robots see and may do, make a mistake on purpose, follow
# the optimal plan, and do the same through the Gymnasium interface.

# %%
from pathlib import Path

import coherent

DEMO = Path(__file__).resolve().parent / "tasks" / "demo.json"
task = coherent.load_tasks(DEMO)[0]
print(task)
print(task.instruction)
print("robots:", task.robot_types)
print("goal:", task.goal, "| type:", task.type, "| ground truth:", task.gt, "steps")

# %% [markdown]
# ## What a robot sees and may do

# %%
env = coherent.Env(task)
dog = next(r for r, kind in task.robot_types.items() if kind == "robot dog")
seen = env.observe(dog)
print(f"the robot dog is in room {seen['room']} and sees {len(seen['nodes'])} things")
for action in env.actions(dog)[:8]:
    print("  ", action)

# %% [markdown]
# ## A mistake: the rules say why, and nothing changes

# %%
quadrotor = next(r for r, kind in task.robot_types.items() if kind == "quadrotor")
wrong = "[grab] <mug>(7)"
print("why not:", env.why_not(quadrotor, wrong))
ok, reason, done = env.step(quadrotor, wrong)
print(ok, reason, done)
print(coherent.parse_action("[puton] <mug>(7) on <coffee table>(10)"))

# %% [markdown]
# ## The optimal plan, one step at a time

# %%
plan = coherent.plan(task)
print(f"{plan['optimal_steps']} steps, a {plan['task_type']} task")
for step in plan["plan"]:
    ok, reason, done = env.step(step["robot"], step["action"])
    print(f"{step['robot']:>3}  {step['action']:<45} {'ok' if ok else reason}")
print("goal satisfied:", env.goal_satisfied())
env.reset()
print("after reset:", env.goal_satisfied())

# %% [markdown]
# ## The same through Gymnasium (`pip install ".[gym]"` from a checkout)

# %%
from coherent.gym import CoherentEnv  # noqa: E402

gym_env = CoherentEnv(task)
observation, info = gym_env.reset(seed=0)
total = 0.0
for step in plan["plan"]:
    observation, reward, terminated, truncated, info = gym_env.step((step["robot"], step["action"]))
    total += reward
print(f"return {total}, terminated {terminated}, truncated {truncated}, after {info['steps']} steps")

# %% [markdown]
# ## When the world changes mid-task (`docs/dynamic.md`)
#
# The demo's events: the robot arm breaks down once the mug is in the basket, and a door
# is locked for two steps. The optimal method replans at each event; stepping its actions
# by hand, `env.news` is what the team was told before the coming step, and
# `env.robots` the team as it now is.

# %%
import tempfile  # noqa: E402

EVENTS = DEMO.parent.parent / "events" / "demo.json"
with tempfile.TemporaryDirectory() as runs:
    episode = coherent.run(task, "optimal", events=str(EVENTS), out=runs)
env = coherent.Env(task, events=str(EVENTS))
for round_ in episode.transcript:
    for news in env.news:
        print(f"before step {env.steps + 1}: {news}")
    decision = round_.get("decision") or {}
    if decision.get("can_do") and decision.get("robot") is not None:
        ok, reason, done = env.step(decision["robot"], decision["action"])
    else:
        ok, reason, done = env.step([])
print(f"{env.steps} steps, as the episode took {episode.steps}; team {sorted(env.robots)}; goal satisfied: {done}")
