"""A per-lane traversal stack whose top entries live in registers.

Dr.Jit's local memory (``dr.alloc_local``) is indexed per lane, so every push is a masked
scatter and every pop a gather: on the development VM's Zen 4 three pushes and a pop cost
55-110 cycles per 16-lane packet, against ~2 cycles for the same pushes as vector selects.
Here the newest REGISTERS entries are loop variables, shifted one place by a select per entry
on each push or pop; only when a lane pushes onto a full set does its oldest register entry
go to local memory (a scatter in a branch that packets skip when no lane spills), and a lane
whose registers are empty pops from local memory. Entries in memory are always older than
those in registers, so the order is a stack's.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

REGISTERS = 4  # stack entries held in loop variables


@dataclass
class LaneStack:
    """A Dr.Jit PyTree (loop state): top[0] is the newest entry; `held` entries are in top,
    `spilled` older ones in the local memory passed to push and pop."""

    # Defaults because Dr.Jit rebuilds PyTrees with an argument-less constructor.
    top: Any = None
    held: Any = None
    spilled: Any = None
    DRJIT_STRUCT = {"top": object, "held": object, "spilled": object}

    @staticmethod
    def empty(dr, uint32, width: int) -> "LaneStack":
        return LaneStack(tuple(dr.zeros(uint32, width) for _ in range(REGISTERS)),
                         dr.zeros(uint32, width), dr.zeros(uint32, width))

    def nonempty(self):
        return (self.held | self.spilled) != 0

    def push(self, dr, memory, value, mask) -> None:
        """Pushes value on the lanes in mask."""
        spill = mask & (self.held == REGISTERS)

        def to_memory(spilled, oldest, spill):
            memory.write(oldest, spilled, spill)
            return spilled + 1

        def stay(spilled, oldest, spill):
            return spilled

        self.spilled = dr.if_stmt((self.spilled, self.top[-1], spill), spill, to_memory, stay)
        top = [dr.select(mask, value, self.top[0])]
        top += [dr.select(mask, self.top[j - 1], self.top[j]) for j in range(1, REGISTERS)]
        self.top = tuple(top)
        self.held = dr.select(mask & ~spill, self.held + 1, self.held)

    def pop(self, dr, memory):
        """Pops the newest entry of every lane (each must hold one; call it in a branch whose
        lanes do)."""
        in_registers = self.held != 0
        from_memory = ~in_registers

        def read(spilled, from_memory):
            return memory.read(dr.select(from_memory, spilled - 1, 0), from_memory)

        def none(spilled, from_memory):
            return dr.zeros(type(spilled), dr.width(spilled))

        stored = dr.if_stmt((self.spilled, from_memory), from_memory, read, none)
        value = dr.select(in_registers, self.top[0], stored)
        top = [dr.select(in_registers, self.top[j + 1], self.top[j])
               for j in range(REGISTERS - 1)]
        self.top = tuple(top + [self.top[-1]])
        self.held = dr.select(in_registers, self.held - 1, self.held)
        self.spilled = dr.select(from_memory, self.spilled - 1, self.spilled)
        return value
