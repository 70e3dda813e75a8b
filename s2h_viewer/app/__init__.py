"""The desktop application: main window, actions, background work, settings (`s2h view`).

numpy's OpenBLAS runs one thread in the application's process: the window's threads (playback, the posing pool,
a video export) call it at once, and its threaded matrix product deadlocked so (a video export while the timeline
played: the GUI thread spinning in ``exec_blas``, the export's blocked in ``dgemm_thread_nn``, for good). The
products it does here (a skin's weights by 16 joint maps) gain nothing from more threads; torch keeps its own.
"""

import numpy  # noqa: F401  loaded first, numpy's and scipy's (each its own OpenBLAS): the limit applies to
import scipy.linalg  # noqa: F401  the BLAS libraries loaded when it is set
from threadpoolctl import threadpool_limits

threadpool_limits(limits=1, user_api="blas")
