"""A retargeting method for the batch tests that kills its worker process on its first attempt: a worker
preloads this file (``preload=``), and so does the test process (to know the method's name). The attempt
count is a marker file named by ``S2H_CRASH_MARKER``, shared by every process of the test."""

from __future__ import annotations

import os
from pathlib import Path

from s2h_viewer.retarget.methods import METHODS, register, retarget_tbs_copy

if "crash_once" not in METHODS:
    @register("crash_once", "Crash once", "TBS Copy after killing its worker the first time it runs")
    def retarget_crash_once(motion, source_hand, target_hand):
        marker = Path(os.environ["S2H_CRASH_MARKER"])
        if not marker.exists():
            marker.write_text(str(os.getpid()))
            os._exit(1)  # the worker dies mid-task, as if killed
        return retarget_tbs_copy(motion, source_hand, target_hand)
