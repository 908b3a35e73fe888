"""The engine's tuning constants, in one place: each was chosen by a measurement recorded in
BENCHMARKS.md (the section named beside it), and none changes a result beyond round-off -
they pick loop modes, chunk sizes and array growth, not physics. The engine modules import
them by name or read them as tuning.NAME where tests and bench/workers_ab.py change them."""

# Below this many particles a CPU runs every loop of the step on one thread (Engine.serial):
# dispatching one parallel loop to Taichi's thread pool costs ~100 us here, two threads save
# ~40 % of the physics. Break-even ~10,000 particles for the chute, ~3,000 for the cooler;
# 5,000 is within ~15 % of the better mode for both. BENCHMARKS.md "Cost curve" (issue 14),
# bench/launch_cost.py.
PARALLEL_FROM = 5000

# The worker threads' particle stage claims chunks of at least WORKER_CHUNK particles, at most
# WORKER_CHUNKS claims per worker and stage (a claim is an atomic on a line both workers hit;
# a particle ~14 ns). BENCHMARKS.md "The rebuild on the workers ... (stop 20)".
WORKER_CHUNK = 128
WORKER_CHUNKS = 16
# True: in the pair stage each worker adds partners' shares to a copy of the sums of its own
# (1.24 - 1.27x the chunk-claiming pair stage at 32k, BENCHMARKS.md stop 18); False: the pair
# stage claims chunks and stores shares at the entries (tests, bench A/B).
WORKER_COPIES = True
# A barrier wait this long (spins, ~0.5 - 1 ms), plus STALL_SPINS_PER_PARTICLE per particle,
# means a worker lost its core (the runs then give way to the parallel kernels); at 128k a fixed
# 20,000 counted 16 % of a lone run's waits. BENCHMARKS.md stop 18.
STALL_SPINS = 20_000
STALL_SPINS_PER_PARTICLE = 0.5
# the start-up check that the workers run at once: give up after this many spins
PROBE_SPINS = 300_000_000
# When more than WORKER_STALL_LIMIT of the barrier waits stalled in WORKER_STALLED_WINDOWS
# windows of WORKER_STALL_WINDOW waits in a row, the threads share the cores with other work
# and the engine goes on with the parallel kernels: alone, 1 - 5 % of the waits stall here;
# beside a busy process 5 - 57 %. BENCHMARKS.md "Tuning constants: the figures that chose them".
WORKER_STALL_LIMIT = 0.08
WORKER_STALL_WINDOW = 2000
WORKER_STALLED_WINDOWS = 2

# Lists that outgrow their arrays (neighbour rows, mesh candidates, pair entries) are
# reallocated at this factor: every reallocation recompiles the kernels that read them (~0.3 -
# 1 s), so a filling scene should reallocate a few times, not at every step of its hold-up.
LIST_GROWTH = 1.5
# The neighbour list of a settled bed of equal spheres holds ~12 entries per particle (both
# directions, within the cutoff 2 r + skin: a 500-bead drum settled at 12.1); a fill poured
# loose starts at ~3 and grew 1644 -> 2508 -> 3933 -> 6045, each growth recompiling the pair
# kernels and the runs of steps. The pair arrays are therefore allocated for at least this
# many entries per alive particle (~100 B each in f64, ~1.5 kB per particle), so such a bed
# allocates once. BENCHMARKS.md "Stop 23".
SETTLED_ENTRIES_PER_PARTICLE = 14

# The gas-gap conduction is tabulated per pair of particle kinds (material, radius) when a scene
# has at most this many kinds (the kernels unroll a lookup over them); beyond, or with radii
# from a distribution, each contact integrates (Gauss-Legendre). BENCHMARKS.md "What gas-gap
# conduction costs" (issue 10 item 8).
MOST_SPECIES = 8

# The serial mode's one-launch rebuild (Broadphase.fused_rebuild) inlines every stage of the
# rebuild into one kernel, which takes 4 - 14 s to compile cold here (1 - 3 s from the kernel
# cache) and is compiled again whenever a list outgrows its array; each rebuild it runs then
# saves a few launches: 0.17 ms median on a 200-bead heap (bench/fused_rebuild_cost.py, five
# rounds, scatter larger than the saving). It pays for itself only after thousands of rebuilds, so it is compiled once the lists have gone this many rebuilds
# in a row without a reallocation; until then rebuilds run as the separate kernels (compiled
# anyway: they grow the arrays). Waiting costs < 0.1 s per growth in a long run; a short run
# (a test, a check) never pays the compile. BENCHMARKS.md "Stop 23".
FUSED_AFTER_QUIET_REBUILDS = 500

# The least particle slots and grid cells the arrays are allocated with (a floor under their
# buckets, setup/memory.py bucket): the arrays' lengths are part of every kernel (Taichi's
# kernel cache keys name the fields' shapes), so small scenes that differ only in their
# counts or domains shared nothing; above the floors they still differ. A suite run's compile
# log (BENCHMARKS.md "Where the compiles go") put 159 kinds of simulation at 131 with these
# floors. They cost memory only (~6 MB in f32, ~10 MB in f64 by setup/memory.py's estimate
# for a scene of a few hundred particles: the slots' state, the first neighbour list sized
# for them, the cell arrays); every loop runs to the counts in use. Results do not change: the grid's cells and every count are the scene's.
MIN_PARTICLE_SLOTS = 4096
MIN_CELL_SLOTS = 16384
# The same for the bodies' triangles (issue 45 item 2): their arrays had each scene's own
# length, so every mesh scene compiled its mesh kernels (the candidate search, the binning,
# the step) afresh: 161 compiles of the candidate search in one suite run, ~30 s. Slots for
# 1,024 triangles cost ~140 kB in f64; the loops run to the scene's count (a runtime value).
MIN_TRIANGLE_SLOTS = 1024

