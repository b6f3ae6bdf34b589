"""The ONNX graph after folding: only the nodes that depend on the image remain.

`fold()` evaluates the whole model once on a probe input. Every tensor that
does not depend on the input (initialisers, Constant nodes, anything computed
from shapes, the DETR masks and position tables, reshape targets, `If`
conditions) becomes a constant; `If` nodes are replaced by the branch their
constant condition selects. The probe's value of every tensor is kept so that
later stages can check their rewrites numerically.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import onnx

from .evaluate import UnsupportedOnnx, attrs_of, initial_values, run_node


@dataclass(eq=False)
class Node:
    op: str
    name: str
    inputs: list
    outputs: list
    attrs: dict = field(default_factory=dict)
    # Macro nodes made by the pattern pass carry their weights here.
    params: dict = field(default_factory=dict)

    def __repr__(self):
        return f"{self.op}({self.name})"


class Graph:
    def __init__(self, nodes, consts, values, input_name, output_names):
        self.nodes = nodes
        self.consts = consts  # name -> np.ndarray for every constant tensor
        self.values = values  # name -> probe value of every tensor
        self.input_name = input_name
        self.output_names = list(output_names)  # current tensor names of the outputs
        self.output_labels = list(output_names)  # the names the model file will use
        self.reindex()

    def reindex(self):
        self.producer = {}
        self.users = {}
        for n in self.nodes:
            for o in n.outputs:
                self.producer[o] = n
            for i in n.inputs:
                self.users.setdefault(i, []).append(n)

    def consumers(self, name: str) -> list:
        return self.users.get(name, [])

    def is_const(self, name: str) -> bool:
        return name in self.consts

    def const(self, name: str):
        return self.consts.get(name)

    def shape(self, name: str) -> tuple:
        return tuple(np.shape(self.values[name]))

    def only_used_by(self, name: str, allowed) -> bool:
        """True if `name` is not a graph output and every consumer is in `allowed`."""
        if name in self.output_names:
            return False
        return all(c in allowed for c in self.consumers(name))

    def rename_uses(self, old: str, new: str):
        for n in self.nodes:
            n.inputs = [new if i == old else i for i in n.inputs]
        self.output_names = [new if o == old else o for o in self.output_names]

    def replace(self, removed, added, position_of=None):
        """Drop `removed` nodes; insert `added` where `position_of` (default: last removed) was."""
        anchor = position_of if position_of is not None else removed[-1]
        out = []
        for n in self.nodes:
            if n is anchor:
                out.extend(added)
            if n not in removed:
                out.append(n)
        self.nodes = out
        self.reindex()


def fold(model: onnx.ModelProto, probe: np.ndarray) -> Graph:
    g = model.graph
    if len(g.input) - len([i for i in g.input if i.name in {t.name for t in g.initializer}]) != 1:
        raise UnsupportedOnnx("the graph must have exactly one non-initialiser input (the image)")
    input_name = next(i.name for i in g.input if i.name not in {t.name for t in g.initializer})
    values = initial_values(model)
    consts = dict(values)
    values[input_name] = probe
    nodes: list = []
    _fold_graph(g, values, consts, nodes)
    outputs = [o.name for o in g.output]
    for o in outputs:
        if o in consts:
            raise UnsupportedOnnx(f"graph output {o!r} does not depend on the input")
    return Graph(nodes, consts, values, input_name, outputs)


def _fold_graph(graph, values, consts, nodes):
    for node in graph.node:
        for i in node.input:
            if i and i not in values:
                raise UnsupportedOnnx(f"node {node.name!r} ({node.op_type}) reads {i!r}, "
                                      "which nothing produces")
        if node.op_type == "If":
            cond = node.input[0]
            if cond not in consts:
                raise UnsupportedOnnx(f"node {node.name!r} (If): the condition depends on the "
                                      "input; only shape-determined branches are supported")
            a = attrs_of(node)
            branch = a["then_branch"] if bool(np.asarray(consts[cond]).reshape(-1)[0]) \
                else a["else_branch"]
            _fold_graph(branch, values, consts, nodes)
            for inner, outer in zip([o.name for o in branch.output], node.output):
                values[outer] = values[inner]
                if inner in consts:
                    consts[outer] = consts[inner]
                else:
                    nodes.append(Node("Identity", node.name + "/inlined", [inner], [outer]))
            continue
        ins = [values[i] if i else None for i in node.input]
        outs = run_node(node, ins)
        is_const = node.op_type in ("Constant", "Shape", "Size") or all(
            (not i) or i in consts for i in node.input)
        for name, v in zip(node.output, outs):
            if name:
                values[name] = v
                if is_const:
                    consts[name] = v
        if not is_const:
            nodes.append(Node(node.op_type, node.name or node.output[0],
                              list(node.input), list(node.output), attrs_of(node)))
