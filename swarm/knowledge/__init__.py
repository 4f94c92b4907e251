"""What robots know: knowledge maps, their merges and change tracking, and the truth tracker.

``maps`` (the ``uint8[R, H, W]`` knowledge rasters, merges, change detection for sharing, the log-odds grid and
the ground-truth exploration tracker), ``packed`` (2-bit copies of a map and the cells changed since) and
``cellcodec`` (the compiled 2-bit and delta byte layouts that copies and map-update payloads share).

May import: ``swarm.base``, ``maps``.
"""
