"""The ACDS emulator's runtime: the launcher, the run monitor/recorder, the direct engine, the run summaries.

The graph itself is declared once in :mod:`acds_common.graph`; both engines here are built from it:
:class:`acds_runtime.launcher.GraphRun` (one OS process per node, over DDS) and
:class:`acds_runtime.direct.DirectRun` (the same steppers in one process, bit-identical data).
"""
