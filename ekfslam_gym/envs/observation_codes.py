"""The observation's fixed indices and scales, shared by the compiled kernel and the Python layout (plain
constants: numba reads them at compile time, and the layout needs them without loading numba)."""

CLIP = 5.0
LANDMARK_FEATURES = 4
COARSE_SAMPLES = 4  # points per side averaged in each cell of the coarse window

PARTS = ("pose", "pose_cov", "landmarks", "globals", "scan", "coverage", "coverage_coarse")
# Positions of the parts in ``ObservationLayout.offsets`` (the kernel reads part i at offsets[i]:offsets[i + 1]).
POSE, POSE_COV, LANDMARKS, GLOBALS, SCAN, COVERAGE, COVERAGE_COARSE = range(len(PARTS))
# Positions in the array of ``observation_constants`` (the kernel's scales and window extents).
MAX_RANGE, SCAN_MAX_RANGE, MEMORY_RESOLUTION, GRID_EXTENT, COARSE_EXTENT = range(5)

# The belief image's channels (``observation.belief_image``): coverage memory, landmark estimates, seen walls.
BELIEF_CHANNELS = 3
BELIEF_COVERAGE, BELIEF_LANDMARKS, BELIEF_WALLS = range(BELIEF_CHANNELS)
