"""One function per `evaluate.py` sub-command, and `run`: check inputs, open the output folder, run the
parts, list what was written. Nothing long starts before the inputs are checked; a user mistake ends
with one line on stderr and exit status 2."""
from __future__ import annotations

import sys

from cyberdog import config as C
from cyberdog.core.learned_set import LearnedSetError
from cyberdog.evaluation import learned as L
from cyberdog.evaluation.check import cmd_check
from cyberdog.evaluation.export import cmd_export
from cyberdog.evaluation.extraction import learned_trajectories, take_recipe_extraction
from cyberdog.evaluation.options import UsageError
from cyberdog.evaluation.output import Run, open_run
from cyberdog.evaluation.pd_match import cmd_pd_match
from cyberdog.evaluation.pick import cmd_pick, refuse_walk_settings
from cyberdog.evaluation.recorded_trot import note_searched_trot, searched_controller, walk_under_recorded_trot
from cyberdog.evaluation.stance_force import cmd_stance_force
from cyberdog.evaluation.walked_robot import walk_config, walked_hardware

BASELINE_COLUMNS = ["trajectory", "speed_command_mps", "mean_speed_mps", "lateral_drift_m", "height_min_m",
                    "height_max_m", "max_roll_rad", "max_pitch_rad", "fell", "energy_J", "energy_per_100m_kJ",
                    "cost_of_transport", "peak_torque_Nm", "peak_joint_speed_radps"]


def trot_of(args, run: Run, cfg: C.WalkConfig, learned, name: str = "config.yaml",
            reference=None) -> C.WalkConfig:
    """`cfg` under the trot the learned paths were recorded under (`walk_under_recorded_trot`), saved as the
    run's `name` where that changed it; a note where the searched shape `reference` was searched under another."""
    walked = walk_under_recorded_trot(args, cfg, learned)
    if walked != cfg:
        run.save_config(walked, name)
    note_searched_trot(reference, walked)
    return walked


# ---- the sub-commands ---------------------------------------------------------------------------------------

def cmd_baselines(args, cfg: C.WalkConfig) -> int:
    from cyberdog.analysis.baselines import baseline_rows
    from cyberdog.analysis.report import markdown_table, write_rows

    run = open_run(args, cfg)
    rows = baseline_rows(cfg, args.speeds, args.trajectories, args.duration)
    write_rows(rows, run.out, "baselines")
    print(markdown_table(rows, BASELINE_COLUMNS))
    return run.finish()


def cmd_extract(args, cfg: C.WalkConfig) -> int:
    from cyberdog.evaluation.parts import run_figures

    if not (args.policies or args.sweep):
        raise UsageError("extract needs --policy PATH (actor file or run folder), --policies ... or --sweep DIR")
    take_recipe_extraction(args)
    L.check_learned_inputs(args)
    run = open_run(args, cfg)
    learned_trajectories(args, run.out, args.speeds, cfg=cfg)  # extracted and saved in run.out/learned/
    run_figures(args.draw_figures, run.out, only=("figure7",))
    return run.finish()


def cmd_compare(args, cfg: C.WalkConfig) -> int:
    from cyberdog.evaluation.parts import run_compare, run_figures

    L.check_learned_inputs(args)
    reference = L.reference_shape(args)
    run = open_run(args, cfg)
    learned = learned_trajectories(args, run.out, args.speeds, cfg=cfg)
    cfg = trot_of(args, run, cfg, learned, reference=reference)
    run_compare(cfg, learned, args.speeds, args.duration, not args.no_same_lift, args.workers, run.out,
                reference=reference, skip_missing=args.skip_missing_paths)
    run_figures(args.draw_figures, run.out, only=("figure10", "figure13"))  # drawn from the files just written
    return run.finish()


def cmd_prototype(args, cfg: C.WalkConfig) -> int:
    from cyberdog.evaluation.parts import run_prototype_part

    L.check_learned_inputs(args)
    reference = L.reference_shape(args, prototype=True)
    run = open_run(args, cfg)
    learned = learned_trajectories(args, run.out, args.speeds, cfg=cfg, for_prototype=True)
    cfg = trot_of(args, run, cfg, learned)  # the searched shape walks under its own trot (run_prototype_part)
    run_prototype_part(cfg, learned, args.speeds, args.prototype_distance, args.prototype_modes, args.workers,
                       run.out, draws=args.prototype_draws, reference=reference, run_up_s=args.prototype_run_up,
                       policies=L.closed_loop_policies(args, learned), hardware=args.hardware,
                       skip_missing=args.skip_missing_paths,
                       pd_matched_from=C.PIDConfig() if args.pd_matched_from_default else None)
    return run.finish()


def cmd_stiffness(args, cfg: C.WalkConfig) -> int:
    from cyberdog.analysis.stiffness import check_scales, run_stiffness, write_stiffness

    L.check_learned_inputs(args)
    try:
        scales = check_scales(args.pd_scales)
    except ValueError as err:
        raise UsageError(f"--pd-scales: {err}") from None
    reference = L.reference_shape(args, prototype=True)
    run = open_run(args, cfg)
    learned = learned_trajectories(args, run.out, args.speeds, cfg=cfg, for_prototype=True)
    cfg = trot_of(args, run, cfg, learned)
    trajectories = {"cycloid": None, "straight": None, **({"searched": reference} if reference is not None else {})}
    rows = run_stiffness(scales, trajectories=trajectories, speeds=args.speeds, distance_m=args.prototype_distance,
                         modes=args.prototype_modes, workers=args.workers, base_cfg=cfg, learned=learned,
                         draws=args.prototype_draws, run_up_s=args.prototype_run_up,
                         policies=L.closed_loop_policies(args, learned), pd_matched=args.pd_matched,
                         hardware=args.hardware, own_trot=searched_controller(reference, cfg.controller))
    print("\n" + write_stiffness(rows, run.out))
    return run.finish()


def cmd_all(args, cfg: C.WalkConfig) -> int:
    from cyberdog.evaluation.parts import run_compare, run_figures, run_prototype_part, run_video

    L.check_learned_inputs(args)
    if args.video:
        check_video_format(args)
    reference = L.reference_shape(args)
    proto_reference = None if args.no_prototype else L.reference_shape(args, prototype=True)
    metrics = L.metrics_files(args.metrics, L.policy_paths(args.policies, args.sweep))
    run = open_run(args, cfg)
    learned = learned_trajectories(args, run.out, args.speeds, cfg=cfg)
    table5_cfg = trot_of(args, run, cfg, learned, reference=reference)
    run_compare(table5_cfg, learned, args.speeds, args.duration, not args.no_same_lift, args.workers, run.out,
                reference=reference, brief=True)
    if not args.no_prototype:  # by default the battery preset's paths where shipped (learned.default_learned)
        given = args.learned or L.policy_paths(args.policies, args.sweep)
        proto_learned = learned if given else learned_trajectories(args, run.out, args.speeds, cfg=cfg,
                                                                     for_prototype=True)
        proto_cfg = table5_cfg if given else walk_under_recorded_trot(args, cfg, proto_learned)
        if proto_cfg != table5_cfg:  # the prototype's paths were recorded under another trot than Table 5's
            run.save_config(proto_cfg, "prototype_config.yaml")
        run_prototype_part(proto_cfg, proto_learned, args.speeds, args.prototype_distance, args.prototype_modes,
                           args.workers, run.out, brief=True, draws=args.prototype_draws, reference=proto_reference,
                           run_up_s=args.prototype_run_up, policies=L.closed_loop_policies(args, proto_learned),
                           hardware=args.hardware)
    run_figures(args.draw_figures, run.out, metrics=metrics)  # drawn from the files just written
    if args.video:
        run_video(table5_cfg, learned, args, run.out)
    return run.finish(headline="table5.md")


def cmd_figures(args, cfg: C.WalkConfig) -> int:
    from cyberdog.evaluation.parts import run_figures

    if getattr(args, "overrides", None) or getattr(args, "config", None):
        raise UsageError("evaluate.py figures draws saved results and walks nothing, so --set and --config change "
                         "nothing; leave them out (the results' own config.yaml says how they were walked)")
    if args.draw_figures is None:
        raise UsageError("figures need the figure code of a checkout: python evaluate.py figures, or python -m plots")
    src = args.from_dir or args.out
    if src is None or not src.is_dir():
        raise UsageError("figures needs --from DIR (a folder written by `evaluate.py` all/compare)")
    out = args.out or src
    run = Run(args, out, append=out.resolve() == src.resolve())  # figures beside the results they draw
    run_figures(args.draw_figures, src, out, metrics=L.metrics_files(args.metrics), learned=args.learned)
    return run.finish()


def check_video_format(args) -> None:
    """An MP4 that cannot be written fails before any frame is rendered."""
    if getattr(args, "video_format", "gif") == "mp4":
        from cyberdog.analysis.video import mp4_writer_problem

        problem = mp4_writer_problem()
        if problem:
            raise UsageError(problem)


def cmd_video(args, cfg: C.WalkConfig) -> int:
    from cyberdog.evaluation.parts import run_video

    check_video_format(args)
    learned = None
    if args.video_trajectory == "learned":
        L.check_learned_inputs(args)
    run = open_run(args, cfg)
    if args.video_trajectory == "learned":  # a policy is rolled out at the video's speed
        learned = learned_trajectories(args, run.out, [args.video_speed], cfg=cfg)
        cfg = trot_of(args, run, cfg, learned)
    run_video(cfg, learned, args, run.out)
    return run.finish()


COMMAND_FUNCTIONS = {"all": cmd_all, "baselines": cmd_baselines, "extract": cmd_extract, "compare": cmd_compare,
                     "prototype": cmd_prototype, "stiffness": cmd_stiffness, "figures": cmd_figures, "video": cmd_video,
                     "check": cmd_check, "pd-match": cmd_pd_match, "stance-force": cmd_stance_force,
                     "export": cmd_export,
                     "pick": cmd_pick}


def run(args, argv: list[str], draw_figures=None) -> int:
    """Run the sub-command `args.command` (parsed by `cyberdog.evaluation.cli.parse_args` from `argv`);
    returns the exit status. draw_figures: `plots.draw_all` or the like (see `parts.run_figures`); None:
    results without figures."""
    args.argv = list(argv)  # as typed, for outputs.json
    args.run = args.walked_hardware = None
    args.draw_figures = draw_figures
    try:
        if args.command == "pick":  # it walks nothing: a walk's settings refused before the config says anything
            refuse_walk_settings(args)
        cfg = walk_config(args)
        args.walked_hardware = walked_hardware(args, cfg)  # config.yaml's hardware section
        return COMMAND_FUNCTIONS[args.command](args, cfg)
    except (UsageError, LearnedSetError) as err:  # LearnedSetError: a learned path unreadable or missing
        _abandon(args, "failed")
        print(f"evaluate.py: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        _abandon(args, "interrupted")
        print("\nevaluate.py: interrupted; the same command runs again into the same --out", file=sys.stderr)
        return 130
    except BaseException:
        _abandon(args, "failed")
        raise


def _abandon(args, status: str) -> None:
    if args.run is not None:
        args.run.abandon(status)


__all__ = ["BASELINE_COLUMNS", "COMMAND_FUNCTIONS", "run"]
