"""The synthetic world with exact ground truth (vcar::synth): worlds, camera rigs, datasets as
`vcar synth` writes them, and the oracle segmenter."""
from ._vcar.synth import (  # noqa: F401
    OracleSegmenter,
    Rig,
    World,
    export_dataset,
    generate_world,
    load_rig,
    load_world,
    make_rig,
    prompt_points,
)
