"""Policies from alpha vectors, and SARSOP's ``.policy`` XML (write and read, so SARSOP's policies work too).

A policy maps a belief to an action: ``action(b) = actions[argmax_k alphas[k] . b]``; ``value(b)`` is the
maximum. File layout (APPL): ``<Policy><AlphaVector vectorLength numObsValue numVectors>`` holding
``<Vector action obsValue>`` (dense) or ``<SparseVector action obsValue>`` with ``<Entry>state value</Entry>``.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from lxml import etree

from ..defaults import MEMORY_LIMIT
from ..errors import PlannerError
from ..files import open_atomic
from ..validation import DECLARED_OPTION, INPUT_OPTION, InputLimits, not_regular
from .io.pomdpx import safe_parser
from .pomdp import POMDP

__all__ = ["AlphaVectorPolicy", "PolicyError", "WRITE_SECONDS", "policy_text", "read_policy", "write_policy"]


class PolicyError(PlannerError):
    """A policy file is malformed or does not fit the model."""


@dataclass(frozen=True)
class AlphaVectorPolicy:
    """``alphas`` (K, S) float, ``actions`` (K,) int: the action of each vector."""

    alphas: np.ndarray
    actions: np.ndarray

    def values(self, belief) -> np.ndarray:
        """``alphas @ belief`` for a dense belief, or for a sparse :class:`FactoredBelief` over the lumped model's
        states (the classes of :mod:`planner.decision.factored_model`)."""
        classes = getattr(belief, "classes", None)
        if classes is not None:
            return self.alphas[:, classes] @ belief.mass
        return self.alphas @ belief

    def action(self, belief: np.ndarray) -> int:
        """The action of the best alpha vector at ``belief``."""
        return int(self.actions[int(np.argmax(self.values(belief)))])

    def value(self, belief: np.ndarray) -> float:
        """The policy's (lower-bound) value at ``belief``."""
        return float(self.values(belief).max())

    def check(self, model: POMDP, source: str = "policy") -> None:
        """Raise :class:`PolicyError` unless the vectors have the model's length and valid actions."""
        self.check_sizes(model.n_states, model.n_actions, source)

    def check_sizes(self, n_states: int, n_actions: int, source: str = "policy") -> None:
        """:meth:`check` against sizes alone (a model whose tables are not built, e.g. the factored one)."""
        if self.alphas.ndim != 2 or self.alphas.shape[1] != n_states:
            raise PolicyError(f"{source}: vectors of length {self.alphas.shape[-1]}, but the model has "
                              f"{n_states} states")
        if self.actions.size and (self.actions.min() < 0 or self.actions.max() >= n_actions):
            bad = int(self.actions.min()) if self.actions.min() < 0 else int(self.actions.max())
            raise PolicyError(f"{source}: action {bad} out of range; the model has {n_actions} actions, "
                              f"numbered 0 to {n_actions - 1}")


# Seconds per number that writing a policy takes (policy_text and the atomic write): 0.45 to 2.2 us measured
# on lumped policies (chain 11: 684 vectors of 5,121 numbers in 1.56 s, 394 in 1.9 s at load average 9;
# complete 7: 968 of 4,803 in 10.3 s at load 12); aplan solve keeps this much of its time limit per number
# of the policy so far, so that the command ends in time on a loaded machine.
WRITE_SECONDS = 2e-6


def policy_text(policy: AlphaVectorPolicy, model_name: str = "aplan") -> str:
    root = etree.Element("Policy", version="0.1", type="value", model=model_name)
    vectors = etree.SubElement(root, "AlphaVector", vectorLength=str(policy.alphas.shape[1]), numObsValue="1",
                               numVectors=str(policy.alphas.shape[0]))
    for alpha, action in zip(policy.alphas, policy.actions):
        # APPL's reader needs the space before </Vector> (without it, it drops every second vector); one
        # %-format per vector: 3.5 times faster than a join (13 million numbers for a 9-part chain)
        etree.SubElement(vectors, "Vector", action=str(int(action)), obsValue="0").text = \
            ("%.12g " * alpha.size) % tuple(alpha.tolist())
    body = etree.tostring(root, pretty_print=True, encoding="unicode")
    return '<?xml version="1.0" encoding="ISO-8859-1"?>\n' + body  # APPL warns about a single-quoted one


def write_policy(policy: AlphaVectorPolicy, path: str | Path, model_name: str = "aplan") -> None:
    """Write a SARSOP-style ``.policy`` file (atomically)."""
    with open_atomic(path) as handle:  # the declared encoding; other characters as XML references
        handle.write(policy_text(policy, model_name).encode("latin-1", "xmlcharrefreplace"))


def read_policy(path: str | Path, model: POMDP | None = None, limits: InputLimits = InputLimits()) -> AlphaVectorPolicy:
    """Read a SARSOP ``.policy`` file; with ``model``, check that it fits. ``limits``: the file's bytes and
    the vector length (the model's states) at most (:class:`~planner.validation.InputLimits`)."""
    source = str(path)
    if not_regular(path, "policy"):
        raise PolicyError(not_regular(path, "policy"))
    try:
        if Path(path).stat().st_size > limits.file_bytes:
            raise PolicyError(f"{source}: {Path(path).stat().st_size:,} bytes, more than the limit of "
                              f"{limits.file_bytes:,} for a policy file ({INPUT_OPTION} raises it)")
        root = etree.fromstring(Path(path).read_bytes(), safe_parser())
    except OSError as exc:
        raise PolicyError(f"{source}: cannot read the file: {exc}") from None
    except etree.XMLSyntaxError as exc:
        raise PolicyError(f"{source}: line {exc.lineno}: malformed XML: {exc.msg}") from None
    block = root.find("AlphaVector")
    if root.tag != "Policy" or block is None:
        raise PolicyError(f"{source}: not a policy file (expected <Policy><AlphaVector>)")
    try:
        length = int(block.get("vectorLength"))
    except (TypeError, ValueError):
        raise PolicyError(f"{source}: line {block.sourceline}: <AlphaVector> needs an integer vectorLength") from None
    if not 1 <= length <= limits.declared:
        raise PolicyError(f"{source}: line {block.sourceline}: vectorLength {length:,}: must be from 1 to "
                          f"{limits.declared:,} (the model's states; {DECLARED_OPTION} raises the limit)")
    alphas, actions = [], []
    for element in block:
        if element.tag not in ("Vector", "SparseVector"):
            continue
        if (len(alphas) + 1) * length > MEMORY_LIMIT // 8:
            raise PolicyError(f"{source}: line {element.sourceline}: more than {len(alphas):,} vectors of "
                              f"{length:,} values, more than {MEMORY_LIMIT // 2 ** 30} GiB")
        values = _vector(element, length, source)
        if values.size != length:
            raise PolicyError(f"{source}: line {element.sourceline}: {values.size} values, vectorLength is {length}")
        try:
            action = int(element.get("action"))
        except (TypeError, ValueError):
            raise PolicyError(f"{source}: line {element.sourceline}: <{element.tag}> needs an integer action, got "
                              f"{element.get('action')!r}") from None
        if action < 0:
            raise PolicyError(f"{source}: line {element.sourceline}: action {action}: actions are numbered from 0")
        alphas.append(values)
        actions.append(action)
    if not alphas:
        raise PolicyError(f"{source}: the policy holds no vectors")
    policy = AlphaVectorPolicy(np.array(alphas), np.array(actions, dtype=np.int64))
    if model is not None:
        policy.check(model, source)
    return policy


def _vector(element, length: int, source: str) -> np.ndarray:
    """The values of a ``<Vector>`` (dense) or ``<SparseVector>`` (``<Entry>index value</Entry>``, indices from
    0 to ``length - 1``); every value finite, else :class:`PolicyError` naming the line. O(length)."""
    where = f"{source}: line {element.sourceline}"
    try:
        if element.tag == "Vector":
            values = np.array([float(x) for x in (element.text or "").split()])
        else:
            values = np.zeros(length)
            for entry in element.findall("Entry"):
                index, value = (entry.text or "").split()
                if not 0 <= int(index) < length:
                    raise PolicyError(f"{where}: <Entry> index {int(index)}: must be from 0 to {length - 1} "
                                      "(vectorLength - 1)")
                values[int(index)] = float(value)
    except (TypeError, ValueError, OverflowError):
        raise PolicyError(f"{where}: malformed <{element.tag}>: expected numbers "
                          f"{'(index value per <Entry>)' if element.tag == 'SparseVector' else ''}") from None
    if not np.isfinite(values).all():
        raise PolicyError(f"{where}: <{element.tag}> holds a value that is not a finite number "
                          f"({values[~np.isfinite(values)][0]}); a policy's values must be finite")
    return values
