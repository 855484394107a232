"""The traversal stack with its top entries in registers (tracer.kernel.lane_stack) is a per-lane
stack: against Python lists, on random pushes and pops in a symbolic loop as the traversal
runs it, deep enough that entries go to local memory and come back."""
from __future__ import annotations

import numpy as np
import pytest

from raycheck.tracer.kernel.backend import import_drjit
from raycheck.tracer.kernel.lane_stack import REGISTERS, LaneStack

LANES = 64
STEPS = 200
DEPTH = 3 * REGISTERS + 5  # local memory entries: more than the registers hold


def script(seed: int, push_share: float) -> tuple[np.ndarray, np.ndarray]:
    """Per step and lane: 1 push, 2 pop (only where the lane's stack is not empty, so that
    every pop is defined), 0 nothing; and the value a push pushes. Lanes are capped at
    REGISTERS + DEPTH entries, the capacity."""
    rng = np.random.default_rng(seed)
    ops = np.zeros((STEPS, LANES), np.uint32)
    values = rng.integers(1, 2**32 - 1, (STEPS, LANES), dtype=np.uint32)
    size = np.zeros(LANES, int)
    for s in range(STEPS):
        r = rng.random(LANES)
        push = (r < push_share) & (size < REGISTERS + DEPTH)
        pop = ~push & (r < push_share + 0.35) & (size > 0)
        ops[s, push], ops[s, pop] = 1, 2
        size += push.astype(int) - pop.astype(int)
    return ops, values


def model(ops: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, int]:
    """The values each pop returns (0 where none) and the deepest stack, by Python lists."""
    popped = np.zeros(ops.shape, np.uint32)
    stacks: list[list[int]] = [[] for _ in range(LANES)]
    deepest = 0
    for s in range(STEPS):
        for lane in range(LANES):
            if ops[s, lane] == 1:
                stacks[lane].append(int(values[s, lane]))
            elif ops[s, lane] == 2:
                popped[s, lane] = stacks[lane].pop()
            deepest = max(deepest, len(stacks[lane]))
    return popped, deepest


def run(ops: np.ndarray, values: np.ndarray) -> np.ndarray:
    dr = import_drjit()
    UInt32 = dr.llvm.UInt32
    op_a, val_a = UInt32(ops.ravel()), UInt32(values.ravel())
    out = dr.zeros(UInt32, STEPS * LANES)
    lane = dr.arange(UInt32, LANES)
    memory = dr.alloc_local(UInt32, DEPTH)

    def cond(step, stack, memory):
        return step < STEPS

    def body(step, stack, memory):
        k = step * LANES + lane
        op = dr.gather(UInt32, op_a, k)
        stack.push(dr, memory, dr.gather(UInt32, val_a, k), op == 1)

        def pop(stack, memory):
            dr.scatter(out, stack.pop(dr, memory), k)
            return stack, memory

        def keep(stack, memory):
            return stack, memory

        stack, memory = dr.if_stmt((stack, memory), op == 2, pop, keep)
        return step + 1, stack, memory

    dr.while_loop((dr.zeros(UInt32, LANES), LaneStack.empty(dr, UInt32, LANES), memory), cond,
                  body)
    return out.numpy().reshape(STEPS, LANES)


@pytest.mark.parametrize("seed,push_share", [(1, 0.45), (2, 0.6), (3, 0.3)])
def test_pops_return_what_a_list_would(seed: int, push_share: float):
    ops, values = script(seed, push_share)
    expected, deepest = model(ops, values)
    if push_share >= 0.45:
        assert deepest > REGISTERS + 2  # entries went to local memory and back
    assert (ops == 2).sum() > 1000
    assert np.array_equal(run(ops, values), expected)
