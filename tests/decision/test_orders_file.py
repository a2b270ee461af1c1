"""The orders in the habits file and on the command line (issue 23; planner/decision/io/habits_file.py version 3,
``aplan habits``, ``--model orders``): the recorded orders are the finished sessions' sequences (closed form: the
ranks played and how often), the Pitman-Yor parameters are written and checked, a session with ``--model orders``
replays to the same beliefs and ``--habits-out`` keeps the orders, and bad input is one clear error naming the
file, nothing written."""
from __future__ import annotations

import json
from collections import Counter

import pytest

from aplan_runner import run_aplan
from planner.assembly import make_plan
from planner.assembly.explode import sequence_at
from planner.decision.factored_model import factored_model
from planner.decision.habits import HabitsError
from planner.decision.io.habits_file import habits_from_dict, habits_to_dict, read_habits
from planner.decision.orders import order_edges
from planner.defaults import ORDERS_CONCENTRATION, ORDERS_DISCOUNT

RANKS = [5, 5, 5, 11]


@pytest.fixture(scope="module")
def learned(pen, tmp_path_factory):
    """Habits of the pen from four sessions (ranks 5, 5, 5, 11), the operator alone."""
    from planner.decision.intention_model import intention_model
    from planner.runtime.log import EventLog
    from planner.runtime.scripted import ScriptedOperator, ScriptedRobot
    from planner.runtime.session import run_session

    folder = tmp_path_factory.mktemp("orders")
    plan = make_plan(pen)
    model = intention_model(plan)

    class Wait:
        wait = len(model.actions) - 1

        def action(self, belief):
            return self.wait

    logs = []
    for k, rank in enumerate(RANKS):
        path = folder / f"s{k}.jsonl"
        assert run_session(model, Wait(), ScriptedOperator(plan, sequence_at(plan, rank)), ScriptedRobot(),
                           EventLog(path)).assembled
        logs.append(path)
    out = folder / "habits.json"
    done = run_aplan("habits", *logs, "-o", out, "--json")
    assert done.returncode == 0, done.stderr
    return plan, logs, out, json.loads(done.stdout)


def test_the_orders_are_the_sessions_sequences(learned):
    plan, _, out, summary = learned
    data = json.loads(out.read_text())
    assert data["version"] == 3 and summary["orders"] == 2
    assert (data["concentration"], data["discount"]) == (ORDERS_CONCENTRATION, ORDERS_DISCOUNT)
    habits = read_habits(out)
    base = factored_model(plan)
    got = {tuple(base.sequence_operations(list(edges))): n for edges, n in order_edges(plan, habits)}
    expected = Counter(tuple(sequence_at(plan, r)) for r in RANKS)
    assert got == {k: float(v) for k, v in expected.items()}
    assert habits_from_dict(habits_to_dict(habits), "again") == habits.__class__(**{**vars(habits), "source": "again"})


def test_parameters_are_written_and_checked(learned, tmp_path):
    _, logs, _, _ = learned
    out = tmp_path / "h.json"
    done = run_aplan("habits", *logs, "-o", out, "--concentration", "2.5", "--discount", "0.3")
    assert done.returncode == 0, done.stderr
    data = json.loads(out.read_text())
    assert (data["concentration"], data["discount"]) == (2.5, 0.3)
    for options, code in ((["--discount", "1"], 2), (["--discount", "nan"], 2), (["--concentration", "inf"], 2),
                          (["--concentration", "-0.95"], 1)):  # a > -d: -0.95 is not above -0.9
        bad = tmp_path / "bad.json"
        done = run_aplan("habits", *logs, "-o", bad, *options)
        assert done.returncode == code and not bad.exists(), (options, done.stderr)
        assert "Traceback" not in done.stderr and ("discount" in done.stderr or "concentration" in done.stderr)


def _write(path, data) -> None:
    path.write_text(data if isinstance(data, str) else json.dumps(data))


@pytest.mark.parametrize("fault, message", [
    ("product", "not of 'Bourjault ballpoint pen'"),
    ("fingerprint", "another version"),
    ("negative", "orders[0]: count -1"),
    ("zero", "orders[0]: count 0 is not above 0"),
    ("not a path", "orders[0], step 1"),
    ("short", "before the finished product"),
    ("discount", "discount d must be at least 0 and below 1"),
    ("concentration", "concentration a must be above"),
    ("prior model", "\"prior_model\" must be"),
    ("version 2 with orders", "need version 3"),
    ("steps", "orders[0]: must be an object"),
])
def test_bad_orders_files_are_refused(learned, tmp_path, fault, message):
    _, _, good, _ = learned
    data = json.loads(good.read_text())
    first = data["orders"][0]
    if fault == "product":
        data["product"] = "a truck"
    elif fault == "fingerprint":
        data["fingerprint"] = "0" * 16
    elif fault == "negative":
        first["count"] = -1
    elif fault == "zero":
        first["count"] = 0
    elif fault == "not a path":
        first["steps"] = first["steps"][1:]
    elif fault == "short":
        first["steps"] = first["steps"][:-1]
    elif fault == "discount":
        data["discount"] = 1.0
    elif fault == "concentration":
        data["concentration"] = -1.0
    elif fault == "prior model":
        data["prior_model"] = "sequences"
    elif fault == "version 2 with orders":
        data["version"] = 2
    elif fault == "steps":
        first["steps"] = []
    bad = tmp_path / "bad.json"
    _write(bad, data)
    out = tmp_path / "model.pomdpx"
    done = run_aplan("pomdp", "pen", "-o", out, "--habits", bad, "--model", "orders")
    assert done.returncode == 1 and message in done.stderr and str(bad) in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_orders_of_an_older_file_are_refused(learned, tmp_path):
    """--model orders needs the orders: a version-2 file (no orders) is refused, naming it."""
    _, _, good, _ = learned
    data = json.loads(good.read_text())
    for key in ("orders", "concentration", "discount", "prior_model"):
        del data[key]
    data["version"] = 1
    old = tmp_path / "old.json"
    _write(old, data)
    assert read_habits(old).orders == ()
    out = tmp_path / "m.pomdpx"
    done = run_aplan("pomdp", "pen", "-o", out, "--habits", old, "--model", "orders")
    assert done.returncode == 1 and "needs the recorded orders" in done.stderr and str(old) in done.stderr
    assert not out.exists()
    with pytest.raises(HabitsError, match="need version 3"):
        habits_from_dict({**data, "discount": 0.5}, "f.json")


def test_an_orders_session_replays_and_keeps_the_orders(learned, pen, tmp_path):
    """A keyboard session with --model orders records the habits with the orders' model; replay rebuilds the
    same beliefs; --habits-out adds the session's order to the file's."""
    plan, _, good, _ = learned
    picks = []
    for op in sequence_at(plan, 5):
        seen = plan.observations[int(plan.operation_observation[op])]
        picks.append(" ".join(seen.parts + ((seen.tool,) if seen.tool else ())))
    log, out = tmp_path / "s.jsonl", tmp_path / "out.json"
    done = run_aplan("session", "pen", "--habits", good, "--model", "orders", "--keyboard", "--planner", "online",
                     "--expansions", "20", "--reward-unfavorable", "-1000", "--reward-favorable", "-1000",
                     "--reward-wrong", "-1000", "--log", log, "--habits-out", out, stdin="\n".join(picks) + "\n")
    assert done.returncode == 0, done.stderr
    recorded = json.loads(log.read_text().splitlines()[0])["settings"]["habits"]
    assert recorded["prior_model"] == "orders" and len(recorded["orders"]) == 2
    replay = run_aplan("replay", log)
    assert replay.returncode == 0 and "beliefs reproduced" in replay.stdout, replay.stdout + replay.stderr
    counts = sorted(o["count"] for o in json.loads(out.read_text())["orders"])
    assert counts == [1, 4]  # rank 5 once more


def test_simulate_and_evaluate_take_the_orders_model(learned, tmp_path):
    """aplan simulate and evaluate run on --model orders (the online planner, a fixed number of expansions); a
    base part with it is refused, naming it."""
    _, _, good, _ = learned
    common = ("--habits", good, "--model", "orders", "--planner", "online", "--expansions", "20")
    done = run_aplan("simulate", "pen", *common, "--random", "2", "--json")
    assert done.returncode == 0, done.stderr
    done = run_aplan("evaluate", "pen", *common, "--episodes", "4", "--operator-sequence", "habitual:5:0.8")
    assert done.returncode == 0 and "4 episodes" in done.stdout, done.stdout + done.stderr
    done = run_aplan("simulate", "pen", *common, "--random", "1", "--base-part", "body")
    assert done.returncode == 1 and "--base-part" in done.stderr and "Traceback" not in done.stderr


def test_the_preset_is_its_parts(learned, tmp_path):
    """--model orders writes the model of the orders with --act-confidence 0.9 (its preset), not the paper's -50."""
    _, _, good, _ = learned

    def model(*options) -> bytes:
        out = tmp_path / f"m{len(list(tmp_path.iterdir()))}.pomdp"
        done = run_aplan("pomdp", "pen", "-o", out, "--habits", good, "--model", "orders", *options)
        assert done.returncode == 0, done.stderr
        return out.read_bytes()

    preset = model()
    assert preset == model("--act-confidence", "0.9") and preset != model("--reward-wrong", "-50")
