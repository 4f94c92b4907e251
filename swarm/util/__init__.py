"""Small shared utilities of the runtime, with no knowledge of robots or maps.

``arena`` (many variable-length arrays in one buffer, for compiled calls), ``jitops`` and ``pymath``
(code-generation controls and CPython's float formulas for numba kernels), ``jit`` (watching numba compile),
``progress`` (progress bars and log lines) and ``source`` (which code made a run).

May import: the standard library and third-party libraries only; nothing of maps, radio or the rest of swarm.
"""
