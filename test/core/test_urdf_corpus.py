"""Every arm, leg and hand chain of example-robot-data against Pinocchio.

A chain (at least 3 moving joints) runs from its mount link (the root, or a link where
moving branches part) to its flange (where moving branches part again, or the last moving
link and the fixed links after it while they do not branch); an arm on a short moving
segment (a torso lift) is also taken from that segment's start. Each is loaded with
``load_urdf`` and compared with Pinocchio's model of the whole URDF (buildModelFromXML),
the joints off the chain where the model holds them (``held_positions``), on rnea, gravity and M at random states: 1e-9
relative; a chain with mimic joints (Romeo's and TALOS' fingers) against Pinocchio's
``mimic=True`` model, or by virtual work where Pinocchio refuses it (support.pinocchio_trees),
every such chain. The tally is printed. Every chain is loaded; in the suite a seeded one of each
file's loaded chains is compared with Pinocchio (every robot, one of its limbs), with
IRB140_SWEEP=full every chain (docs/development.md).
"""

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from irb140_dynamics.core import ModelError, gravity, mass_matrix, rnea
from irb140_dynamics.core.urdf import load_urdf

from ..support.common import full_sweep
from ..support.pinocchio_trees import corpus_files, pinocchio_state
from ..support.pinocchio_trees import worst_error as mimic_worst_error

MOVING = ("revolute", "continuous", "prismatic")
MIN_JOINTS = 3
RTOL = 1e-9
STATES = 3


def chains(text: str) -> list[tuple[str, str]]:
    """(base, tip) of each chain of the URDF (see the module)."""
    robot = ET.fromstring(text)
    children: dict[str, list[tuple[str, str]]] = {}
    parents = set()
    for joint in robot.findall("joint"):
        parent, child = joint.find("parent").get("link"), joint.find("child").get("link")
        children.setdefault(parent, []).append((joint.get("type"), child))
        parents.add(child)
    roots = [link.get("name") for link in robot.findall("link") if link.get("name") not in parents]
    if len(roots) != 1:
        return []
    moving_below = _moving_below(roots[0], children)

    def branches(link):
        return [(kind, child) for kind, child in children.get(link, ()) if kind in MOVING or moving_below[child]]

    segments = []  # (start, moving joints, tip, ends at a branching link)
    stack = [roots[0]]
    while stack:
        start = stack.pop()
        for kind, link in branches(start):
            count, last = kind in MOVING, link if kind in MOVING else None
            while len(branches(link)) == 1:
                kind, link = branches(link)[0]
                if kind in MOVING:
                    count, last = count + 1, link
            if branches(link):
                stack.append(link)
                segments.append((start, count, link))
                continue
            while last is not None and len(children.get(last, ())) == 1 and children[last][0][0] == "fixed":
                last = children[last][0][1]
            segments.append((start, count, last))
    found = [(start, tip) for start, count, tip in segments if count >= MIN_JOINTS]
    short = {tip: start for start, count, tip in segments if 0 < count < MIN_JOINTS}
    found += [(short[start], tip) for start, count, tip in segments if start in short and count > 0]
    return found


def with_the_followed_joints(text: str, base: str, tip: str) -> str:
    """The lowest link above ``base`` whose tree takes in every joint the chain's mimic
    joints follow (Romeo's hand joint beside its fingers, TALOS' gripper joint)."""
    robot = ET.fromstring(text)
    parent_joint = {joint.find("child").get("link"): joint for joint in robot.findall("joint")}
    by_name = {joint.get("name"): joint for joint in robot.findall("joint")}

    def up(link):  # the link and its ancestors, the link first
        links = [link]
        while links[-1] in parent_joint:
            links.append(parent_joint[links[-1]].find("parent").get("link"))
        return links

    chain = up(tip)[: up(tip).index(base) + 1]
    mimics = [parent_joint[link].find("mimic") for link in chain[:-1]]
    wanted = {mimic.get("joint") for mimic in mimics if mimic is not None}
    leaders = [by_name[name].find("parent").get("link") for name in wanted if name in by_name]
    return next(link for link in up(base) if all(link in up(leader) for leader in leaders))


def _moving_below(root, children) -> dict[str, int]:
    order, stack = [], [root]
    while stack:
        link = stack.pop()
        order.append(link)
        stack += [child for _, child in children.get(link, ())]
    below: dict[str, int] = {}
    for link in reversed(order):
        below[link] = sum((kind in MOVING) + below[child] for kind, child in children.get(link, ()))
    return below


def worst_error(text: str, base: str, tip: str, rng, loaded=None) -> float:
    """The largest relative difference from Pinocchio over STATES random states; ``loaded``
    the chain's load_urdf result already made (else loaded here)."""
    loaded = loaded or load_urdf(text, base, tip)
    model, held = loaded.model, loaded.held_positions  # the joints off the chain where the model holds them
    if model.mimics is not None:
        return mimic_worst_error(text, model, rng, STATES, held)
    full = pin.buildModelFromXML(text)
    data = full.createData()
    names = model.joint_names
    index = [full.joints[full.getJointId(name)].idx_v for name in names]
    damping, friction = full.damping[index], full.friction[index]
    worst = 0.0
    for _ in range(STATES):
        q, qd, qdd = rng.uniform(-1.5, 1.5, model.n), rng.uniform(-2, 2, model.n), rng.uniform(-3, 3, model.n)
        pq, v, a = pinocchio_state(full, names, q, qd, qdd, held)
        tau = pin.rnea(full, data, pq, v, a)[index] + damping * qd + friction * np.tanh(qd / model.smoothing_velocity)
        g = pin.computeGeneralizedGravity(full, data, pq)[index]
        M = pin.crba(full, data, pq)
        M = (np.triu(M) + np.triu(M, 1).T)[np.ix_(index, index)]
        for ours, theirs in ((rnea(model, q, qd, qdd), tau), (gravity(model, q), g), (mass_matrix(model, q), M)):
            worst = max(worst, float(np.max(np.abs(ours - theirs)) / max(1.0, np.max(np.abs(theirs)))))
    return worst


def run_corpus(files, rng, compared_per_file: int | None = None) -> dict[str, list[str]]:
    """Every chain of ``files`` loaded; of the chains that load, ``compared_per_file`` per
    file (chosen by ``rng``; all when None) compared with Pinocchio."""
    tally: dict[str, list[str]] = {"agree": [], "mimic": [], "refused": [], "disagree": [], "crash": []}
    for path in files:
        text = Path(path).read_text()
        loaded, mimics = [], []  # every chain with mimic joints compared
        models = {}  # label -> the chain as loaded (None: a tree, loaded when compared)
        for base, tip in chains(text):
            label = f"{path.split('/robots/')[-1]} {base} -> {tip}"
            try:
                chain = load_urdf(text, base, tip)
                mimic = chain.model.mimics is not None
            except ModelError as refusal:
                if "<mimic>" not in str(refusal) or "\n" in str(refusal):
                    tally["refused"].append(f"{label}: {refusal}")
                    continue
                # refused: the tree from the link above the joints they follow
                base, tip = with_the_followed_joints(text, base, tip), None
                label, mimic, chain = f"{label} (the tree below {base})", True, None
            except Exception as crash:  # counted and shown
                tally["crash"].append(f"{label}: {type(crash).__name__}: {crash}")
                continue
            models[label] = chain
            (mimics if mimic else loaded).append((label, base, tip))
        if compared_per_file is not None and len(loaded) > compared_per_file:
            loaded = [loaded[k] for k in sorted(rng.choice(len(loaded), compared_per_file, replace=False))]
        for label, base, tip in loaded + mimics:
            try:
                error = worst_error(text, base, tip, rng, models[label])
            except Exception as crash:  # counted and shown
                tally["crash"].append(f"{label}: {type(crash).__name__}: {crash}")
                continue
            kind = ("mimic" if (label, base, tip) in mimics else "agree") if error <= RTOL else "disagree"
            tally[kind].append(f"{label}: {error:.1e}")
    return tally


FILES = corpus_files()


@pytest.mark.slow
@pytest.mark.skipif(not FILES, reason="example-robot-data is not installed")
def test_every_chain_of_example_robot_data_agrees_with_pinocchio():
    full = full_sweep()
    tally = run_corpus(FILES, np.random.default_rng(22), compared_per_file=None if full else 1)
    print("\nexample-robot-data chains: " + ", ".join(f"{len(v)} {k}" for k, v in tally.items()))
    for kind in ("refused", "disagree", "crash"):
        for line in tally[kind]:
            print(f"  {kind}: {line}")
    assert len(tally["agree"]) >= (150 if full else 50)  # the corpus is there, its chains found
    assert len(tally["mimic"]) >= 16  # its mimic chains (romeo's fingers, talos' grippers)
    assert not tally["refused"] and not tally["disagree"] and not tally["crash"], tally["disagree"] + tally["crash"]
