"""The web service: FastAPI app, routes, and the services that own time and machines."""

import os

# One BLAS thread in every process of ours, set before numpy loads (worker processes inherit
# it): our matrices are tiny (a drive's 11 × 11 matrix exponential), and OpenBLAS' helper
# threads spin while they wait. Beside a SCHED_FIFO worker loop on two cores they starve
# until the kernel's real-time throttling lets them run, and one expm took a second.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
# We use no pydantic plugins; looking for them reads every installed package's metadata,
# about a quarter of a second of each process' start (gateway, every worker, each CLI call).
os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")

VERSION = "0.2.0"
