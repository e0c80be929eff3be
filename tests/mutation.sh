#!/usr/bin/env bash
# Mutation testing of the modules that define jaxlens's published results (not run in CI).
#
#   python3 -m venv /work/mutvenv && /work/mutvenv/bin/pip install -e '.[test,mutation]'
#   MUTMUT=/work/mutvenv/bin/mutmut PY=/work/mutvenv/bin/python tests/mutation.sh [module ...]
#
# Runs mutmut 2 on each module with its own fast test selection (a mutant costs seconds),
# in a scratch copy of the tracked files (mutmut edits files in place), and prints per module
# the mutants generated, killed and surviving. Module keys: see the table below; default all.
# RETEST=1 re-runs only the survivors (and untested mutants) of an earlier run in $WORK against
# the current tests. Don't run `mutmut show` in $WORK while a run is going (it corrupts the
# cache); copy .mutmut-cache and jaxlens/ elsewhere first. Results: tests/MUTATION.md.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
MUTMUT=${MUTMUT:-mutmut}
PY=${PY:-python}
WORK=${WORK:-/tmp/jaxlens-mutation}
T=tests/test_design_answers.py
D=tests/test_design.py
declare -A FILE SEL ONLY
FILE[mask]=jaxlens/design/mask.py
SEL[mask]="$T::test_field_weights_use_the_area_weighted_mean $D::test_reweighting_mask $T::test_run_applies_mask_and_regularizers_per_stage"
FILE[regularizers]=jaxlens/design/regularizers.py
SEL[regularizers]="$T::test_obliquity_residuals_are_the_hinge_of_the_cosines_on_both_sides $T::test_slope_residuals_are_the_hinge_of_the_parabola_slope $T::test_spacing_residuals_use_both_sags_and_the_image $T::test_clear_radii_are_the_largest_valid_heights $D::test_soft_hinge_is_a_hinge_near_the_bound_and_never_overflows $D::test_spacing_and_slope_zero_inside_and_pull_back_outside $D::test_obliquity_zero_inside_and_pull_back_outside"
FILE[losses]=jaxlens/design/losses.py
SEL[losses]="tests/test_design_residuals.py tests/test_edof_base_lens.py::test_spec_efl_checks_and_objective_residual $T::test_paper_stage_defaults_and_float32_sampling $T::test_spot_loss_is_measured_from_the_ideal_image_point_f_tan $T::test_ideal_image_height_follows_the_image_mapping_and_weights_are_normalised $T::test_failed_rays_cost_half_the_pupil $T::test_centroid_reference_and_pin $T::test_launch_fields_and_stage_args"
# ImageObjective renders a scene (seconds per call): its mutants are not run here.
ONLY[losses]="StageArgs,radial_area_weights,half_pupil,RayLoss,launch,SpotResult,spot_errors,Aux,design_residuals,Objective"
FILE[curriculum]=jaxlens/design/curriculum.py
SEL[curriculum]="$T::test_stage_defaults_and_short_sine_paths $T::test_paper_stage_defaults_and_float32_sampling $T::test_launch_fields_and_stage_args $T::test_run_applies_mask_and_regularizers_per_stage $D::test_sine_path_paper_schedule $D::test_paper_stages $D::test_run_stops_on_nonfinite_loss $D::test_run_drops_nonfinite_designs"
# The design loop's plumbing (devices, progress bar, logging) is left out: run's mask and
# regularizer hand-off is checked through stage_args and _reweight, which it calls.
ONLY[curriculum]="sine_path,Stage,paper_stages,stage_args,_reweight"
FILE[evaluate]=jaxlens/design/evaluate.py
SEL[evaluate]="tests/test_evaluate.py"
FILE[edof_losses]=jaxlens/experiments/edof/losses.py
SEL[edof_losses]="tests/test_edof.py::test_losses_on_known_values tests/test_edof.py::test_loss_shape_errors"
FILE[edof_metrics]=jaxlens/experiments/edof/evaluate.py
SEL[edof_metrics]="tests/test_edof.py::test_table2_rec_metrics_come_from_the_reconstruction tests/test_edof.py::test_placements_cycle_over_the_frame_blocks tests/test_edof.py::test_bootstrap_gain_over_seeds_and_crops"
ONLY[edof_metrics]="evaluate,_one,placements,depth_key,bootstrap_gain"
FILE[image_metrics]=jaxlens/io/images.py
SEL[image_metrics]="tests/test_images.py::test_scenes_psnr_ssim tests/test_images.py::test_psnr_default_range_is_the_span_of_both_images_and_zero tests/test_edof.py::test_table2_rec_metrics_come_from_the_reconstruction"
ONLY[image_metrics]="psnr,ssim,_data_range"
FILE[nets]=jaxlens/nets.py
N=tests/test_nets.py
SEL[nets]="$N::test_default_architecture_and_its_bounds $N::test_block_with_nonzero_scales_matches_numpy $N::test_block_widths_are_the_papers_expansions $N::test_network_with_nonzero_scales_matches_numpy $N::test_fresh_block_is_identity $N::test_layernorm2d_normalises_each_pixel_over_channels $N::test_simple_gate_multiplies_the_two_halves $N::test_depthwise_matches_grouped_convolution $N::test_strided_conv_halves_and_pixel_shuffle_doubles $N::test_bad_options_raise $N::test_default_is_small_and_options_scale_it $N::test_nafnet_keeps_shape_and_pads_odd_sizes $N::test_initialisation_is_pytorch_default_and_keeps_the_dtype $N::test_building_under_jit_is_refused"
FILE[zmx_writer]=jaxlens/io/zmx_write.py
SEL[zmx_writer]="tests/test_zmx.py tests/test_corpus.py tests/test_toroid_paraxial.py::test_zmx_round_trip_is_exact tests/test_mirrors_coordbreaks.py::test_zmx_with_mirrors_and_coordinate_breaks_round_trips tests/test_lensfile.py::test_materials_and_apertures"
ONLY[zmx_writer]="_z,_zemax_catalog,_formula,_schott_fit,_nd_vd,_sanitize,_GlassWriter,surface_lines,dumps,save_zmx"
ALL="mask regularizers losses curriculum evaluate edof_losses edof_metrics image_metrics nets zmx_writer"

if [[ -n "${RETEST:-}" ]]; then
    # Re-test only the surviving mutants of an earlier run in $WORK against the current tests.
    cp -r "$ROOT/tests/." "$WORK/tests/"
else
    rm -rf "$WORK" && mkdir -p "$WORK"
    (cd "$ROOT" && git ls-files -z | xargs -0 -I{} cp --parents {} "$WORK/")
    cp "$ROOT/mutmut_config.py" "$WORK/"
fi
cd "$WORK"
export JAX_COMPILATION_CACHE_DIR=${JAX_COMPILATION_CACHE_DIR:-$WORK/.jaxcache}
export JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0
for key in ${@:-$ALL}; do
    sel=${SEL[$key]}
    # SCOPE=f,g (one module) narrows the run to those functions, e.g. to finish an earlier run.
    [[ -n "${SCOPE:-}" ]] && ONLY[$key]=$SCOPE
    echo "== $key: ${FILE[$key]} (only: ${ONLY[$key]:-all}) $(date -u +%FT%TZ)"
    runner="env PYTHONPATH=$WORK $PY -m pytest -x -q -n 0 -p no:cacheprovider $sel"
    if [[ -n "${RETEST:-}" ]]; then
        ids=$("$PY" -c "import sqlite3; db = sqlite3.connect('.mutmut-cache'); print(' '.join(
            str(r[0]) for r in db.execute('select m.id from mutant m join line l on m.line = l.id '
            'join sourcefile s on l.sourcefile = s.id where s.filename = ? and m.status in '
            '(\"bad_survived\", \"untested\")', ('${FILE[$key]}',))))")
        for id in $ids; do
            MUTATE_ONLY=${ONLY[$key]:-} "$MUTMUT" run "$id" --paths-to-mutate "${FILE[$key]}" --tests-dir tests \
                --runner "$runner" \
                >> "$WORK/$key.retest.log" 2>&1 || true
        done
    else
        MUTATE_ONLY=${ONLY[$key]:-} "$MUTMUT" run --paths-to-mutate "${FILE[$key]}" \
            --tests-dir tests --runner "$runner" > "$WORK/$key.log" 2>&1 || true
    fi
    "$MUTMUT" results > "$WORK/$key.results" 2>&1 || true
    "$PY" - "${FILE[$key]}" <<'PYEOF'
import sqlite3, sys
db = sqlite3.connect(".mutmut-cache")
rows = db.execute(
    "select m.status, count(*) from mutant m join line l on m.line = l.id "
    "join sourcefile s on l.sourcefile = s.id where s.filename = ? group by m.status",
    (sys.argv[1],)).fetchall()
st = dict(rows)
tested = sum(v for k, v in st.items() if k not in ("skipped", "untested"))
# mutmut's "suspicious" mutants failed the tests (slowly): they count as killed.
killed = st.get("ok_killed", 0) + st.get("ok_suspicious", 0)
print(f"{sys.argv[1]}: generated {tested} (skipped {st.get('skipped', 0)}, untested "
      f"{st.get('untested', 0)}), killed {killed}, survived {st.get('bad_survived', 0)}, "
      f"timed out {st.get('bad_timeout', 0)}")
PYEOF
done
