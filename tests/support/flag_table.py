"""Every option of every `langgap` verb, and how its effect is checked.

`FLAG_CHECKS` maps `"VERB [SUBVERB] --option"` to the checks that show the option does something. The fast
layer (`tests/unit/test_flag_table.py`) fails when an option of the parser has no entry (or an entry names an
option that is gone), and when a `ProvenBy` names a test that does not exist or never mentions the option;
`tests/test_flags.py` runs every `Differs` and `Refused`.

Placeholders in argument lists: `{catalog}` the `short_catalog` registry; `{dir}` a fresh directory of the
invocation's own (an output, a run); `{stored}` / `{same}` / `{reseeded}` three one-episode `noop` runs on the
short catalog (`{same}` with `{stored}`'s spec, `{reseeded}` with another seed); `{collection}` a path that
holds no collection.
"""

from __future__ import annotations

import argparse
import ast
import re
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class Differs:
    """`base` and `base + added` differ in their exit status, stdout, `error:` line, progress bar, stored
    episodes or the files they write."""

    base: tuple[str, ...]
    added: tuple[str, ...]
    broken: str = ""  # known broken: the check is a strict xfail with this reason
    path: str | None = None  # PATH for both invocations (None: unchanged)


@dataclass(frozen=True)
class Refused:
    """`argv` exits 2 with one `error:` line holding `message`, and writes nothing under `{dir}`."""

    argv: tuple[str, ...]
    message: str
    broken: str = ""


@dataclass(frozen=True)
class ProvenBy:
    """A test elsewhere proves the option's effect (`tests/test_x.py::test_name`); it must exist and mention
    the option (as `--option`, or as the keyword `option=` of the API it reaches), itself or through a helper
    of `tests/support` it calls."""

    test: str


Check = Differs | Refused | ProvenBy

SHORT_TASK = "spatial/s0/black-bowl-1-on-plate"
_EVAL = ("eval", "--policy", "noop", "--catalog", "{catalog}", "--run", "{dir}/run", "--workers", "0")
_REPORT = ("report", "{stored}", "--no-published")
_VALIDATE = (
    *("validate", SHORT_TASK, "--catalog", "{catalog}", "--inits", "1", "--policy", "noop", "--workers", "0"),
    "--no-progress",
)
_CLAIMS = ("validate", SHORT_TASK, "--catalog", "{catalog}", "--inits", "1", "--claims-only")
_GENERATE = ("generate", "--out", "{dir}/registry.yaml", "--suites", "goal")
_COLLECT = (
    *("collect", "--catalog", "{catalog}", "--tasks", SHORT_TASK, "--demos", "1", "--out", "{dir}/demos"),
    *("--max-attempts", "1", "--workers", "0", "--no-progress"),
)
_SMALL_BC = ("train", "small-bc", "--data", "{collection}", "--out", "{dir}/bc.safetensors")
_LEROBOT = ("train", "lerobot", "exp1", "--dataset-root", "{dir}/data", "--output-dir", "{dir}/out", "--dry-run")
_EXPERIMENT = ("experiment", "run", "exp1", "--out", "{dir}/exp1", "--dry-run")
_EXPERIMENT_CHAIN = "tests/test_lerobot_experiment.py::test_act_experiment_runs_end_to_end_and_resumes"
_SHORT_COLLECTION = (
    "tests/test_experiments.py::"
    "test_a_short_collection_stops_the_experiment_unless_allowed_and_the_summary_says_what_was_kept"
)
_TINY_SMOLVLM = "tests/test_lerobot_experiment.py::test_smolvla_experiment_trains_on_a_tiny_smolvlm_built_here"

_EVAL_FLAGS = "tests/test_eval.py::test_every_flag_of_a_run_reaches_its_effect"
_VALIDATE_CLI = "tests/test_validate.py::test_cli_validate_writes_report_and_records_verdicts"
_GENERATE_GATE = "tests/test_generate.py::test_generate_gates_every_candidate_and_records_how"
_GENERATE_CLI = "tests/test_generate.py::test_cli_generate_writes_a_loadable_registry_and_prints_counts"
_REPLAY = "tests/test_search.py::test_tasks_replay_replays_a_verdicts_demonstrations_and_fails_a_damaged_one"
_REMAKE = "tests/test_search.py::test_tasks_replay_remake_keeps_what_does_the_task_here_and_leaves_the_rest"
_SPLITS = "tests/unit/test_splits.py::test_generate_writes_a_file_that_shows_and_checks"
_SPLIT_WORDS = "tests/unit/test_splits.py::test_novel_word_splits_hold_out_a_sentence_with_a_word_training_never_says"
_AUDIT = "tests/test_external.py::test_audit_runs_the_start_check_on_k_init_states_and_records_it_beside_the_registry"
_COLLECT_CLI = "tests/test_demos.py::test_collect_cli_without_lerobot_writes_compact_form"
_CLAIMS_EXECUTION = "tests/test_validate.py::test_claims_only_runs_its_probes_on_the_execution_flags"
_SWITCH_GATE = "tests/test_switch_gate.py::test_the_switch_gate_records_counts_and_marks_verdicts_per_task_and_k"
_RAY_WORK = "tests/test_ray.py::test_every_kind_of_work_runs_on_a_worker_node_that_sees_another_disk"
_SMALL_BC_CLI = "tests/test_small_bc.py::test_training_is_deterministic_and_checkpoint_round_trips"
_SMALL_VLA = ("train", "small-vla", "--data", "{collection}", "--out", "{dir}/vla.safetensors")
_SMALL_VLA_CLI = "tests/test_small_vla.py::test_training_is_deterministic_and_checkpoint_round_trips"
_SMALL_VLA_ERRORS = "tests/test_small_vla.py::test_what_cannot_be_trained_or_loaded_is_a_clear_error"
_HDF5_CLI = "tests/test_hdf5.py::test_cli_refuses_to_overwrite_and_rejects_what_is_not_a_collection"
_SERVE = "tests/test_flags.py::test_serve_binds_the_host_and_port_it_is_given"
_SHARED_ROLLOUTS = "tests/test_shared_rollouts.py::test_shared_rollouts_give_each_episode_its_own_record"
_CHECK_POLICY_CLI = "tests/test_check_policy.py::test_the_oracle_passes_from_the_command_line_with_every_flag"
_LEROBOT_EXPORT = "tests/test_lerobot_demos.py::test_export_lerobot_cli_writes_the_dataset_it_is_told"


def _gate_without_inits(flag: tuple[str, ...]) -> Refused:
    return Refused((*_GENERATE, *flag), f"{flag[0]} only apply to the feasibility gate (--gate-inits K)")


def _claims_refuse(flag: tuple[str, ...]) -> Refused:
    return Refused(
        (*_CLAIMS, *flag),
        f"--claims-only runs no policy: it stores no episodes, records no verdicts and searches nothing "
        f"(drop {flag[0]})",
    )


FLAG_CHECKS: dict[str, tuple[Check, ...]] = {
    # -- tasks ------------------------------------------------------------------------------------------
    "tasks list --catalog": (Differs(("tasks", "list"), ("--catalog", "{catalog}")),),
    "tasks list --style": (Differs(("tasks", "list"), ("--style", "paper")),),
    "tasks list --suite": (Differs(("tasks", "list"), ("--suite", "libero_goal")),),
    "tasks list --kind": (Differs(("tasks", "list"), ("--kind", "original")),),
    "tasks list --dimension": (Differs(("tasks", "list"), ("--dimension", "spatial_description")),),
    "tasks list --split": (Differs(("tasks", "list"), ("--split", "heldout")),),
    "tasks list --tasks": (Differs(("tasks", "list"), ("--tasks", "spatial")),),
    "tasks list --json": (Differs(("tasks", "list"), ("--json",)),),
    "tasks show --catalog": (Differs(("tasks", "show", SHORT_TASK), ("--catalog", "{catalog}")),),
    "tasks show --style": (Differs(("tasks", "show", SHORT_TASK), ("--style", "paper")),),
    "tasks show --json": (Differs(("tasks", "show", SHORT_TASK), ("--json",)),),
    "tasks show --bddl": (Differs(("tasks", "show", SHORT_TASK), ("--bddl",)),),
    "tasks gate --catalog": (Differs(("tasks", "gate"), ("--catalog", "{catalog}")),),
    "tasks gate --tasks": (Differs(("tasks", "gate"), ("--tasks", "spatial")),),
    "tasks gate --markdown": (Differs(("tasks", "gate"), ("--markdown",)),),
    "tasks gate --condition": (Differs(("tasks", "gate"), ("--condition", "switch:20")), ProvenBy(_SWITCH_GATE)),
    "tasks replay --catalog": (ProvenBy(_REPLAY),),
    "tasks replay --tasks": (ProvenBy(_REPLAY),),
    "tasks replay --remake": (ProvenBy(_REMAKE),),
    "tasks audit --catalog": (Differs(("tasks", "audit", "--tasks", "spatial/s0/*"), ("--catalog", "libero-pro")),),
    "tasks audit --tasks": (Differs(("tasks", "audit", "--catalog", "libero-pro"), ("--tasks", "spatial/s0/*")),),
    "tasks audit --examples": (Differs(("tasks", "audit", "--catalog", "libero-pro"), ("--examples", "0")),),
    "tasks audit --starts": (
        ProvenBy(_AUDIT),
        Refused(("tasks", "audit", "--catalog", "libero-pro", "--starts", "-1"), "--starts must be 0"),
    ),
    "tasks audit --record": (ProvenBy(_AUDIT),),
    "tasks audit --references": (
        ProvenBy("tests/test_reference_check.py::test_the_left_moka_pot_is_right_but_in_the_raw_render"),
        Refused(("tasks", "audit", "--catalog", "libero-pro", "--references", "-1"), "--references must be 0"),
    ),
    "tasks audit --html": (ProvenBy("tests/test_audit_page.py::test_the_audit_page_in_a_real_browser"),),
    # -- eval -------------------------------------------------------------------------------------------
    "eval --policy": (Refused(("eval", "--policy", "gpt-robot", "--run", "{dir}/run"), "unknown policy"),),
    "eval --policy-arg": (
        Refused((*_EVAL, "--policy", "random", "--policy-arg", "temperature=3"), "no argument 'temperature'"),
    ),
    "eval --catalog": (ProvenBy(_EVAL_FLAGS),),
    "eval --style": (ProvenBy(_EVAL_FLAGS),),
    "eval --tasks": (ProvenBy(_EVAL_FLAGS),),
    "eval --episodes": (ProvenBy(_EVAL_FLAGS), Refused((*_EVAL, "--episodes", "51"), "out of range")),
    "eval --run": (ProvenBy(_EVAL_FLAGS),),
    "eval --workers": (ProvenBy(_EVAL_FLAGS),),
    "eval --resume": (
        ProvenBy("tests/test_eval.py::test_kill_minus_nine_and_resume_loses_and_duplicates_nothing"),
        ProvenBy("tests/test_eval.py::test_a_resume_keeps_every_condition_s_stored_episodes"),
    ),
    "eval --extend": (
        ProvenBy("tests/test_eval.py::test_resume_skips_done_and_extend_grows_the_run"),
        Refused((*_EVAL, "--extend"), "--extend needs --resume"),
    ),
    "eval --condition": (ProvenBy(_EVAL_FLAGS),),
    "eval --video": (
        ProvenBy("tests/test_eval.py::test_videos_of_the_first_episodes_are_written"),
        Refused((*_EVAL, "--video", "most:3"), "most:3"),
    ),
    "eval --seed": (ProvenBy(_EVAL_FLAGS),),
    "eval --stepping": (ProvenBy("tests/test_stepping.py::test_eval_records_the_fast_stepping_it_ran"),),
    "eval --seed-scheme": (ProvenBy("tests/test_parity.py::test_eval_records_the_openpi_seed_scheme_and_uses_it"),),
    "eval --repeats": (
        ProvenBy("tests/test_eval.py::test_repeats_run_every_episode_with_more_seeds_and_reports_the_spread"),
        Refused((*_EVAL, "--repeats", "0"), "--repeats must be between 1"),
    ),
    "eval --timeout": (ProvenBy(_EVAL_FLAGS), Refused((*_EVAL, "--timeout", "5"), "--timeout needs worker processes")),
    "eval --max-attempts": (ProvenBy("tests/test_eval.py::test_a_run_that_ends_with_gaps_exits_3"),),
    "eval --max-failure-streak": (ProvenBy("tests/test_eval.py::test_a_run_that_ends_with_gaps_exits_3"),),
    "eval --backend": (
        ProvenBy("tests/test_ray.py::test_cluster_run_survives_a_killed_worker_and_equals_the_local_backend"),
    ),
    "eval --ray-address": (
        ProvenBy("tests/test_ray.py::test_cluster_run_survives_a_killed_worker_and_equals_the_local_backend"),
        Refused((*_EVAL, "--ray-address", "127.0.0.1:1"), "--ray-address needs --backend ray"),
    ),
    "eval --share-rollouts": (
        Differs(_EVAL, ("--share-rollouts",)),
        ProvenBy(_SHARED_ROLLOUTS),
        ProvenBy("tests/test_shared_rollouts.py::test_a_policy_that_reads_its_instruction_never_shares_a_rollout"),
    ),
    "eval --shared-policy": (
        ProvenBy(
            "tests/test_local_batching.py::test_two_workers_sharing_one_batching_policy_give_the_episodes_of_unshared_workers"
        ),  # noqa: E501
    ),
    "eval --max-batch": (
        ProvenBy(
            "tests/test_local_batching.py::test_two_workers_sharing_one_batching_policy_give_the_episodes_of_unshared_workers"
        ),  # noqa: E501
        Refused((*_EVAL, "--max-batch", "2"), "--max-batch only apply to a shared policy"),
    ),
    "eval --max-wait-ms": (
        ProvenBy(
            "tests/test_local_batching.py::test_two_workers_sharing_one_batching_policy_give_the_episodes_of_unshared_workers"
        ),  # noqa: E501
        Refused((*_EVAL, "--max-wait-ms", "2"), "--max-wait-ms only apply to a shared policy"),
    ),
    "eval --policy-gpus": (
        ProvenBy("tests/test_ray.py::test_policy_gpus_beyond_the_cluster_is_an_error_before_anything_is_stored"),
        Refused((*_EVAL, "--policy-gpus", "1"), "--policy-gpus only apply to a shared policy"),
    ),
    "eval --no-progress": (ProvenBy(_EVAL_FLAGS),),
    "eval --quiet": (ProvenBy(_EVAL_FLAGS),),
    # -- check-policy -----------------------------------------------------------------------------------
    "check-policy --policy-arg": (
        Refused(("check-policy", "random", "--policy-arg", "temperature=3"), "no argument 'temperature'"),
        Refused(("check-policy", "oracle", "--policy-arg", "noise=-1"), "noise must be >= 0"),  # reaches the policy
    ),
    "check-policy --catalog": (ProvenBy(_CHECK_POLICY_CLI),),
    "check-policy --style": (ProvenBy(_CHECK_POLICY_CLI),),
    "check-policy --tasks": (ProvenBy(_CHECK_POLICY_CLI),),
    "check-policy --episodes": (
        ProvenBy(_CHECK_POLICY_CLI),
        Refused(("check-policy", "noop", "--episodes", "51"), "out of range"),
    ),
    "check-policy --timeout": (
        ProvenBy(_CHECK_POLICY_CLI),
        Refused(("check-policy", "noop", "--timeout", "0"), "--timeout must be positive"),
    ),
    "check-policy --budget": (
        ProvenBy("tests/test_check_policy.py::test_the_episode_is_played_whole_and_the_page_says_how_much"),
        Refused(("check-policy", "noop", "--budget", "0"), "--budget must be positive"),
    ),
    # -- serve ------------------------------------------------------------------------------------------
    "serve --policy": (ProvenBy(_SERVE),),
    "serve --policy-arg": (
        ProvenBy("tests/test_openpi.py::test_langgap_serve_gives_each_connection_its_own_policy"),
        Refused(("serve", "--policy", "random", "--port", "1", "--policy-arg", "oops"), "key=value"),
    ),
    "serve --host": (ProvenBy(_SERVE),),
    "serve --port": (ProvenBy(_SERVE),),
    # -- report (report_cmd.py: another branch fixes --summary's --format / --allow-mismatch) ---------------
    "report --compare": (Differs(_REPORT, ("--compare", "{same}")),),
    "report --format": (
        Differs(_REPORT, ("--format", "json")),
        Refused((*_REPORT, "--summary", "--format", "json"), "--summary shows the diagnosis as md or latex"),
        Differs((*_REPORT, "--summary"), ("--format", "latex")),
        Differs(("report", "--pool", "a={stored}"), ("--format", "csv")),
    ),
    "report --summary": (Differs(_REPORT, ("--summary",)),),
    "report --pool": (
        ProvenBy("tests/unit/test_pooled.py::test_the_cli_prints_the_pooled_table_in_the_format_asked"),
        Differs(("report", "--pool", "a={stored}"), ("--pool", "b={same}")),
        Refused((*_REPORT, "--pool", "a={same}"), "--pool prints the pooled table only"),
    ),
    "report --no-published": (Differs(("report", "{stored}"), ("--no-published",)),),
    "report --allow-mismatch": (
        Differs((*_REPORT, "--compare", "{reseeded}"), ("--allow-mismatch",)),
        Differs(
            (*_REPORT, "--summary", "--compare", "{reseeded}"),
            ("--allow-mismatch",),
        ),
        Differs(("report", "--pool", "a={stored},{reseeded}"), ("--allow-mismatch",)),
    ),
    "report --split": (
        ProvenBy("tests/unit/test_report_split.py::test_the_pools_and_the_report_group_by_the_split_in_its_order"),
        Differs(_REPORT, ("--split", "langgap99-instruction")),
        Differs(("report", "--pool", "a={stored}"), ("--split", "langgap99-instruction")),
        Refused((*_REPORT, "--split", "nope"), "unknown split 'nope'"),
    ),
    "report --html": (Differs(_REPORT, ("--html", "{dir}/html")),),
    "report --plots": (Differs(_REPORT, ("--plots", "{dir}/plots")),),
    "report --episodes": (Differs(_REPORT, ("--episodes", "{dir}/episodes.csv")),),
    # -- validate -------------------------------------------
    "validate --catalog": (ProvenBy(_VALIDATE_CLI),),
    "validate --inits": (ProvenBy(_VALIDATE_CLI),),
    "validate --policy": (ProvenBy(_VALIDATE_CLI), _claims_refuse(("--policy", "blind"))),
    "validate --blind": (Differs(_VALIDATE, ("--blind",)),),
    "validate --share-rollouts": (
        ProvenBy("tests/test_shared_rollouts.py::test_validate_blind_shares_the_blind_rollouts_only"),
        _claims_refuse(("--share-rollouts",)),
    ),
    "validate --claims-only": (
        ProvenBy("tests/test_validate.py::test_claims_only_resets_every_task_without_a_policy"),
    ),
    "validate --out": (ProvenBy(_VALIDATE_CLI),),
    "validate --condition": (
        ProvenBy(_SWITCH_GATE),
        Refused((*_VALIDATE, "--condition", "given"), "--condition takes switch:K only"),
        _claims_refuse(("--condition", "switch:5")),
    ),
    "validate --record": (ProvenBy(_VALIDATE_CLI),),
    "validate --workers": (
        Refused((*_VALIDATE, "--workers", "-1"), "--workers must be at least 0"),
        ProvenBy(_CLAIMS_EXECUTION),
    ),
    "validate --run": (Differs(_VALIDATE, ("--run", "{dir}/run")), _claims_refuse(("--run", "{dir}/run"))),
    "validate --resume": (
        Refused(
            (*_VALIDATE, "--resume"),
            "--resume needs --run",
        ),
    ),
    "validate --no-progress": (Differs(_VALIDATE[:-1], ("--no-progress",)),),
    "validate --search-budget": (
        ProvenBy("tests/test_validate.py::test_a_search_budget_that_cannot_take_effect_is_refused"),
        _claims_refuse(("--search-budget", "3")),
    ),
    "validate --stepping": (Differs((*_VALIDATE, "--run", "{dir}/run"), ("--stepping", "fast")),),
    "validate --backend": (ProvenBy(_RAY_WORK),),
    "validate --ray-address": (
        ProvenBy(_RAY_WORK),
        Refused((*_VALIDATE, "--ray-address", "127.0.0.1:1"), "--ray-address needs --backend ray"),
    ),
    "validate --timeout": (
        ProvenBy(_CLAIMS_EXECUTION),
        Refused((*_VALIDATE, "--timeout", "5"), "--timeout needs worker processes"),
    ),
    "validate --max-attempts": (Refused((*_VALIDATE, "--max-attempts", "0"), "--max-attempts must be at least 1"),),
    "validate --max-failure-streak": (ProvenBy(_CLAIMS_EXECUTION),),
    # -- generate ---------------------------------------------------------------------------------------
    "generate --catalog": (Differs(_GENERATE, ("--catalog", "langgap-beyond")),),
    "generate --out": (ProvenBy(_GENERATE_CLI),),
    "generate --suites": (ProvenBy(_GENERATE_CLI),),
    "generate --gate-inits": (
        ProvenBy(_GENERATE_GATE),
        Refused((*_GENERATE, "--gate-inits", "-1"), "--gate-inits must be at least 0"),
    ),
    "generate --workers": (ProvenBy(_GENERATE_GATE), _gate_without_inits(("--workers", "2"))),
    "generate --run": (_gate_without_inits(("--run", "{dir}/run")),),
    "generate --resume": (_gate_without_inits(("--resume", "--run", "{dir}/run")),),
    "generate --no-progress": (ProvenBy(_GENERATE_GATE), _gate_without_inits(("--no-progress",))),
    "generate --search-budget": (_gate_without_inits(("--search-budget", "0")),),
    "generate --stepping": (ProvenBy(_GENERATE_GATE), _gate_without_inits(("--stepping", "fast"))),
    "generate --backend": (_gate_without_inits(("--backend", "ray")),),
    "generate --timeout": (_gate_without_inits(("--timeout", "5")),),
    "generate --max-attempts": (_gate_without_inits(("--max-attempts", "2")),),
    "generate --max-failure-streak": (_gate_without_inits(("--max-failure-streak", "2")),),
    "generate --ray-address": (_gate_without_inits(("--ray-address", "127.0.0.1:1")),),
    "collect --backend": (ProvenBy(_RAY_WORK),),
    "collect --ray-address": (
        ProvenBy(_RAY_WORK),
        Refused((*_COLLECT, "--ray-address", "127.0.0.1:1"), "--ray-address needs --backend ray"),
    ),
    "collect --timeout": (Refused((*_COLLECT, "--timeout", "5"), "--timeout needs worker processes"),),
    "collect --max-task-attempts": (
        Refused((*_COLLECT, "--max-task-attempts", "0"), "--max-task-attempts must be at least 1"),
    ),
    "collect --max-failure-streak": (
        Refused((*_COLLECT, "--max-failure-streak", "0"), "--max-failure-streak must be at least 1"),
    ),
    # -- collect ---------------------------------------------
    "collect --catalog": (Refused((*_COLLECT, "--catalog", "{dir}/nowhere.yaml"), "nowhere.yaml"),),
    "collect --style": (Differs(_COLLECT, ("--style", "paper")),),
    "collect --tasks": (ProvenBy(_COLLECT_CLI),),
    "collect --demos": (ProvenBy(_COLLECT_CLI), Refused((*_COLLECT, "--demos", "0"), "--demos must be at least 1")),
    "collect --out": (ProvenBy(_COLLECT_CLI),),
    "collect --workers": (ProvenBy(_COLLECT_CLI),),
    "collect --seed": (ProvenBy(_COLLECT_CLI),),
    "collect --noise": (
        ProvenBy(
            "tests/test_small_bc.py::test_a_task_collected_without_success_is_skipped_and_an_uncollected_one_is_an_error"
        ),  # noqa: E501
    ),
    "collect --max-attempts": (
        ProvenBy(
            "tests/test_small_bc.py::test_a_task_collected_without_success_is_skipped_and_an_uncollected_one_is_an_error"
        ),  # noqa: E501
    ),
    "collect --format": (ProvenBy(_COLLECT_CLI),),
    "collect --no-progress": (ProvenBy(_COLLECT_CLI),),
    # -- verify-demos, export-lerobot, export-hdf5 ---------------------------------------------------------
    "export-lerobot --workers": (ProvenBy(_LEROBOT_EXPORT),),
    "export-lerobot --no-progress": (ProvenBy(_LEROBOT_EXPORT),),
    "export-lerobot --image-size": (
        ProvenBy("tests/test_lerobot_demos.py::test_frames_are_oriented_as_lerobots_libero_processor_makes_them"),
        Refused(("export-lerobot", "{collection}", "--image-size", "8"), "image size must be in 16..1024"),
    ),
    "export-hdf5 --out": (ProvenBy(_HDF5_CLI),),
    "export-hdf5 --images": (ProvenBy("tests/test_hdf5.py::test_images_are_upright_renders_of_the_recorded_states"),),
    "export-hdf5 --workers": (
        ProvenBy("tests/test_hdf5.py::test_images_are_upright_renders_of_the_recorded_states"),
        Refused(("export-hdf5", "{collection}", "--workers", "2"), "--workers is about rendered images"),
    ),
    "export-hdf5 --image-size": (
        ProvenBy("tests/test_small_vla.py::test_images_are_exported_at_the_asked_size"),
        Refused(("export-hdf5", "{collection}", "--image-size", "64"), "--image-size is about rendered images"),
        Refused(("export-hdf5", "{collection}", "--images", "--image-size", "8"), "image size must be in 16..1024"),
    ),
    "export-hdf5 --force": (ProvenBy(_HDF5_CLI),),
    "export-hdf5 --resume": (
        ProvenBy("tests/test_hdf5.py::test_resume_keeps_the_finished_files_and_writes_the_rest"),
        Refused(("export-hdf5", "{collection}", "--resume", "--force"), "--force replaces the existing files"),
    ),
    "export-hdf5 --no-progress": (ProvenBy(_HDF5_CLI),),
    # -- train ------------------------------------------------------------------------------------------
    "train small-bc --config": (Refused((*_SMALL_BC, "--config", "{dir}/absent.yaml"), "absent.yaml"),),
    "train small-bc --data": (ProvenBy(_SMALL_BC_CLI),),
    "train small-bc --catalog": (
        Refused((*_SMALL_BC, "--catalog", "{catalog}"), "--catalog only says where --tasks' selection is looked up"),
        Refused((*_SMALL_BC, "--catalog", "{catalog}", "--tasks", "goal"), "matches no task in catalog short"),
    ),
    "train small-bc --tasks": (Refused((*_SMALL_BC, "--tasks", "levitate"), "levitate"),),
    "train small-bc --out": (ProvenBy(_SMALL_BC_CLI),),
    "train small-bc --steps": (ProvenBy(_SMALL_BC_CLI),),
    "train small-bc --batch-size": (ProvenBy(_SMALL_BC_CLI),),
    "train small-bc --lr": (ProvenBy("tests/test_flags.py::test_small_bc_training_options_reach_the_config"),),
    "train small-bc --seed": (ProvenBy("tests/test_flags.py::test_small_bc_training_options_reach_the_config"),),
    "train small-bc --threads": (ProvenBy(_SMALL_BC_CLI),),
    "train small-bc --loss": (ProvenBy("tests/test_flags.py::test_small_bc_training_options_reach_the_config"),),
    "splits generate --catalog": (ProvenBy(_SPLITS),),
    "splits generate --heldout": (ProvenBy(_SPLITS),),
    "splits generate --name": (ProvenBy(_SPLITS),),
    "splits generate --out": (ProvenBy(_SPLITS),),
    "splits generate --subsets": (ProvenBy(_SPLITS),),
    "splits generate --tasks": (ProvenBy(_SPLITS),),
    "splits generate --seed": (ProvenBy("tests/unit/test_splits.py::test_a_generated_compositional_split_does_too"),),
    "splits generate --style": (ProvenBy(_SPLIT_WORDS),),
    "splits check --demos": (
        ProvenBy("tests/test_demos.py::test_a_split_check_finds_the_held_out_goals_a_collection_passes_through"),
    ),
    "splits show --json": (ProvenBy(_SPLITS),),
    "train small-bc --vocabulary": (ProvenBy("tests/test_small_bc.py::test_the_vocabulary_is_fixed_before_training"),),
    "train small-bc --device": (
        ProvenBy("tests/test_flags.py::test_small_bc_training_options_reach_the_config"),
        Refused((*_SMALL_BC, "--device", "meta"), "--device meta: only cpu and cuda are supported"),
    ),
    "train small-vla --config": (ProvenBy(_SMALL_VLA_ERRORS),),
    "train small-vla --data": (ProvenBy(_SMALL_VLA_CLI),),
    "train small-vla --catalog": (
        Refused((*_SMALL_VLA, "--catalog", "{catalog}"), "--catalog only says where --tasks' selection is looked up"),
    ),
    "train small-vla --tasks": (Refused((*_SMALL_VLA, "--tasks", "levitate"), "levitate"),),
    "train small-vla --out": (ProvenBy(_SMALL_VLA_CLI),),
    "train small-vla --steps": (ProvenBy(_SMALL_VLA_CLI),),
    "train small-vla --batch-size": (ProvenBy(_SMALL_VLA_CLI),),
    "train small-vla --lr": (ProvenBy("tests/test_flags.py::test_small_bc_training_options_reach_the_config"),),
    "train small-vla --seed": (ProvenBy("tests/test_flags.py::test_small_bc_training_options_reach_the_config"),),
    "train small-vla --threads": (ProvenBy(_SMALL_VLA_CLI),),
    "train small-vla --loss": (ProvenBy("tests/test_flags.py::test_small_bc_training_options_reach_the_config"),),
    "train small-vla --vocabulary": (ProvenBy("tests/test_small_bc.py::test_the_vocabulary_is_fixed_before_training"),),
    "train small-vla --device": (
        ProvenBy("tests/test_flags.py::test_small_bc_training_options_reach_the_config"),
        Refused((*_SMALL_VLA, "--device", "meta"), "--device meta: only cpu and cuda are supported"),
    ),
    "train lerobot --dataset-root": (Differs(_LEROBOT, ("--dataset-root", "{dir}/other")),),
    "train lerobot --dataset-repo-id": (Differs(_LEROBOT, ("--dataset-repo-id", "me/demos")),),
    "train lerobot --output-dir": (Differs(_LEROBOT, ("--output-dir", "{dir}/elsewhere")),),
    "train lerobot --set": (Differs(_LEROBOT, ("--set", "steps=7")),),
    "train lerobot --dry-run": (Differs(_LEROBOT[:-1], ("--dry-run",), path=""),),
    "train lerobot --policy": (Differs(_LEROBOT, ("--policy", "act")),),
    "train lerobot --tuning": (
        Differs(_LEROBOT, ("--tuning", "language")),
        Refused((*_LEROBOT, "--tuning", "nope"), "pi05 has no tuning 'nope'"),
    ),
    # -- experiment ----------------------------------------------------------------------------------------------
    "experiment run --out": (ProvenBy(_EXPERIMENT_CHAIN),),
    "experiment run --dry-run": (ProvenBy(_EXPERIMENT_CHAIN),),
    "experiment run --policy": (Differs(_EXPERIMENT, ("--policy", "act")),),
    "experiment run --tuning": (Differs(_EXPERIMENT, ("--tuning", "language")),),
    "experiment run --tiny": (
        Differs(_EXPERIMENT, ("--policy", "act", "--tiny")),
        Refused((*_EXPERIMENT, "--tiny"), "pi05 has no tiny version"),
    ),
    "experiment run --catalog": (Refused((*_EXPERIMENT, "--catalog", "{dir}/nowhere.yaml"), "nowhere.yaml"),),
    "experiment run --demos": (Differs(_EXPERIMENT, ("--demos", "2")),),
    "experiment run --steps": (Differs(_EXPERIMENT, ("--steps", "7")),),
    "experiment run --episodes": (Differs(_EXPERIMENT, ("--episodes", "2")),),
    "experiment run --eval-sets": (
        Differs(_EXPERIMENT, ("--eval-sets", "trained")),
        Refused((*_EXPERIMENT, "--eval-sets", "trained,nope"), "--eval-sets takes trained, heldout, original"),
    ),
    "experiment run --image-size": (Differs(_EXPERIMENT, ("--image-size", "128")),),
    "experiment run --seed": (Differs(_EXPERIMENT, ("--seed", "3")),),
    "experiment run --noise": (Differs(_EXPERIMENT, ("--noise", "0.3")),),
    "experiment run --allow-short": (ProvenBy(_SHORT_COLLECTION),),
    "experiment run --originals": (Refused((*_EXPERIMENT, "--originals", "{dir}/none"), "not a LeRobot dataset"),),
    "experiment run --device": (Differs(_EXPERIMENT, ("--device", "cpu")),),
    "experiment run --workers": (Differs(_EXPERIMENT, ("--workers", "2")),),
    "experiment run --set": (Differs(_EXPERIMENT, ("--set", "batch_size=4")),),
    "experiment tiny-smolvlm --image-size": (ProvenBy(_TINY_SMOLVLM),),
}


def cli_options() -> set[str]:
    """Every option of every verb of the `langgap` parser, as `"VERB [SUBVERB] --option"` (its long form)."""
    from langgap.cli.main import build_parser

    found: set[str] = set()

    def walk(parser: argparse.ArgumentParser, prefix: str) -> None:
        for action in parser._actions:  # argparse lists its actions only in this private field
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    walk(sub, f"{prefix} {name}".strip())
            elif action.option_strings and not isinstance(action, argparse._HelpAction):
                found.add(f"{prefix} {max(action.option_strings, key=len)}")

    walk(build_parser(), "")
    return found


def proof_problem(test: str, option: str) -> str | None:
    """Why `test` (`tests/test_x.py::test_name`) does not prove `option`'s effect, or None when it may."""
    path, _, name = test.partition("::")
    source = (REPO / path).read_text() if (REPO / path).is_file() else None
    if source is None:
        return f"{path} does not exist"
    functions = {n.name: n for n in ast.walk(ast.parse(source)) if isinstance(n, ast.FunctionDef)}
    if name not in functions:
        return f"{path} has no {name}"
    test_function = functions[name]
    fixtures = {a.arg for a in test_function.args.args}
    # What the test and its module's fixtures call: a fixture may build its output through a helper.
    callers = [test_function, *(functions[f] for f in fixtures if f in functions)]
    calls = [n for f in callers for n in ast.walk(f) if isinstance(n, ast.Call)]
    called = {n.func.id for n in calls if isinstance(n.func, ast.Name)}
    # The test with its parametrisation, the fixtures it takes and the helpers it calls (its module's own, and
    # those of tests/support).
    texts = [ast.get_source_segment(source, d) or "" for d in test_function.decorator_list]
    texts += [ast.get_source_segment(source, functions[n]) or "" for n in {name, *called, *fixtures} if n in functions]
    for helper in (REPO / "tests/support").glob("*.py"):
        text = helper.read_text()
        texts += [
            ast.get_source_segment(text, n) or "" for n in ast.parse(text).body if getattr(n, "name", "") in called
        ]
    keyword = option.lstrip("-").replace("-", "_") + "="
    as_flag = re.compile(rf"(?<![\w-]){re.escape(option)}(?![\w-])")
    if not any(as_flag.search(text) or keyword in text for text in texts):
        return f"{test} never mentions {option} (nor {keyword})"
    return None
