"""Two code-generation controls for compiled kernels whose hot loop is a chain of dependent float steps.

``select(cond, a, b)`` is ``a if cond else b`` as one LLVM ``select`` instruction. numba lowers Python's
conditional expression to branches; LLVM may keep them, and a branch taken at random (which of two grid
boundaries a ray crosses next) mispredicts about half the time.

``opaque(x)`` returns ``x`` unchanged, through an empty inline-assembly statement that LLVM cannot see into.
Without it LLVM rewrites ``select(c, t + d, t + 0.0)`` as ``t + select(c, d, 0.0)``: the same value, but the
select then sits between the comparison and the addition, so a loop that carries ``t`` waits for both in
turn. Hiding the two sums keeps both additions off that chain: each iteration waits for the comparison and
one select only (see :func:`swarm.world.sensing._lidar_advance`).

Neither changes a value: ``select`` computes both operands and picks one, ``opaque`` emits no instruction.
On machines other than x86-64 and AArch64 ``opaque`` is the identity without the barrier (the register
constraint is architecture-specific), so kernels give the same bits there, only with the longer chain.
"""

from __future__ import annotations

import platform
from typing import Any

from llvmlite import ir
from numba import types
from numba.extending import intrinsic

_FLOAT_REGISTER = {"x86_64": "x", "amd64": "x", "aarch64": "w", "arm64": "w"}.get(platform.machine().lower())
"""Inline-assembly constraint letter of a floating-point register on this machine (None: unknown)."""


@intrinsic
def select(typingctx: Any, cond: Any, a: Any, b: Any) -> Any:
    """``a if cond else b`` without a branch; ``a`` and ``b`` of one type (both are computed)."""
    if a != b or not isinstance(cond, types.Boolean):
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        c, x, y = args
        return builder.select(c, x, y)

    return a(types.boolean, a, a), codegen


@intrinsic
def opaque(typingctx: Any, x: Any) -> Any:
    """``x`` (a float), opaque to LLVM's optimiser: no rewrite can move work across it."""
    if not isinstance(x, types.Float):
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        (value,) = args
        if _FLOAT_REGISTER is None:
            return value
        barrier = ir.InlineAsm(ir.FunctionType(value.type, [value.type]), "", f"={_FLOAT_REGISTER},0")
        return builder.call(barrier, [value])

    return x(x), codegen


__all__ = ["opaque", "select"]
