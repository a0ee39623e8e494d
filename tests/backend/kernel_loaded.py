"""Imported by the test services' fork server (tests/backend/forked.py): the kernel is loaded
and warmed up there once. Every service forked from it forks its worker zygote from itself
(backend/workers/zygote.py), which then finds the kernel loaded, as a zygote does after its
first worker, instead of loading it for each of the run's services."""

from backend.workers.warmup import warm_up

warm_up()
