import time
t=time.perf_counter()
from tests.probes.warm_up import other_transports
from orchestrator.coupling.fmi.structure import block_arguments
from orchestrator.coupling.step import compile_step
import numpy as np
compile_step(block_arguments([], [], [], [], [], [], [], [], 0.0)); print("fmu", time.perf_counter()-t, flush=True); t=time.perf_counter()
compile_step((np.zeros(1, dtype=np.int64),)); print("python", time.perf_counter()-t, flush=True)
