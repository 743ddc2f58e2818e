"""identify --payload-only: the payload's mass, CoM and inertia, the arm's own parameters
(links, friction, rotor inertia) taken from --params-file or --urdf as they are.

Prints the payload with standard deviations; writes --out, the arm's parameter file with
``payload.*`` identified (whole or not at all). See docs/load.md.
"""

from __future__ import annotations

import argparse
import shlex

from irb140_dynamics.tools.cli import ToolError, check_model_paths, input_path, output_file, refuse_input_as_output
from irb140_dynamics.tools.common import model_inputs

NOT_WITH_PAYLOAD_ONLY = ("validate", "plots", "urdf_out", "offsets", "held_out", "prior_weight")  # None: not given


def identify_payload(args: argparse.Namespace, argv: list[str], interrupts) -> int:
    if not (args.params_file or args.urdf):
        raise ToolError("--payload-only: give the arm's model: --params-file ARM.yaml (or --urdf ARM.urdf)")
    for name in NOT_WITH_PAYLOAD_ONLY:
        if getattr(args, name):
            raise ToolError(f"--{name.replace('_', '-')}: not with --payload-only")
    recording = input_path(args.recording)
    check_model_paths(args)
    out = output_file(args.out)
    refuse_input_as_output([(args.recording, recording), *model_inputs(args)], [(args.out, out)])

    from irb140_dynamics.identification.payload import fit_payload
    from irb140_dynamics.identification.payload_report import payload_file, payload_summary
    from irb140_dynamics.identification.pipeline import IdentificationSettings
    from irb140_dynamics.tools.common import arm_of, reading_progress
    from irb140_dynamics.tools.outputs import Outputs

    source = arm_of(args, chain_for="identify --payload-only")
    arm = source.model
    settings = IdentificationSettings(topic=args.topic, cutoff=args.cutoff, min_speed=args.min_speed)
    progress = None if args.quiet else reading_progress("identify")
    with Outputs(interrupts) as outputs:
        fit = fit_payload(arm, args.recording, settings, progress)
        print(f"arm: {source.origin}")
        print(payload_summary(fit, arm), flush=True)
        outputs.text(
            out,
            args.out,
            payload_file(fit, arm, shlex.join(["identify", *argv]), source.origin if source.urdf else None),
        )
        for typed in outputs.commit():
            print(f"wrote {typed}")
    return 0
