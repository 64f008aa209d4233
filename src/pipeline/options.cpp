#include "ffcube/pipeline/options.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>

#include "ffcube/core/error.hpp"
#include "ffcube/hemicube/layout.hpp"

namespace ffcube {

RowMethod parse_row_method(std::string_view text) {
    if (text == "hemicube") return RowMethod::Hemicube;
    if (text == "raycast") return RowMethod::Raycast;
    throw InputError(fmt::format("--method {}: must be hemicube or raycast", text));
}

Correction parse_correction(std::string_view text) {
    if (text == "none") return Correction::None;
    if (text == "near") return Correction::Near;
    throw InputError(fmt::format("--correct {}: must be near or none", text));
}

FarFieldMode parse_far_field(std::string_view text) {
    if (text == "auto") return FarFieldMode::automatic;
    if (text == "on") return FarFieldMode::on;
    if (text == "off") return FarFieldMode::off;
    throw InputError(fmt::format("--far-field {}: must be auto, on or off", text));
}

void parse_exact_visibility(std::string_view text, RowOptions& o) {
    if (text == "auto") {
        o.exact_visibility_auto = true;
        return;
    }
    o.exact_visibility_auto = false;
    if (text == "off") {
        o.exact_visibility_occluders = 0;
        return;
    }
    std::size_t k = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), k);
    if (text.empty() || ec != std::errc{} || end != text.data() + text.size())
        throw InputError(fmt::format("--exact-visibility {}: must be auto, off or a number of occluders 0..{}", text,
                                     kMaxExactVisibilityOccluders));
    o.exact_visibility_occluders = k;  // its range: validate(RowOptions)
}

FineRows parse_fine_rows(std::string_view text) {
    if (text == "auto") return FineRows::automatic;
    if (text == "hemicubes") return FineRows::hemicubes;
    if (text == "rays") return FineRows::rays;
    throw InputError(fmt::format("--fine-rows {}: must be auto, hemicubes or rays", text));
}

ContactCuts parse_contact_cuts(std::string_view text) {
    if (text == "auto") return ContactCuts::Auto;
    if (text == "on") return ContactCuts::On;
    if (text == "off") return ContactCuts::Off;
    throw InputError(fmt::format("--contact-cuts {}: must be auto, on or off", text));
}

bool cuts_contacts(const SceneOptions& o) {
    return o.contact_cuts == ContactCuts::On || (o.contact_cuts == ContactCuts::Auto && o.subdivide);
}

const char* to_string(ContactCuts c) {
    switch (c) {
        case ContactCuts::Auto: return "auto";
        case ContactCuts::On: return "on";
        case ContactCuts::Off: return "off";
    }
    return "";
}

EnforceRequest parse_enforce_request(std::string_view text) {
    if (text.empty()) return EnforceRequest::None;
    if (text == "reciprocity") return EnforceRequest::Reciprocity;
    if (text == "closure") return EnforceRequest::Closure;
    if (text == "both") return EnforceRequest::Both;
    throw InputError(fmt::format("--enforce {}: must be reciprocity, closure or both", text));
}

void set_row_method(std::string_view text, RowOptions& o) {
    if (text == "auto") {
        o.method_auto = true;
        return;
    }
    try {
        o.method = parse_row_method(text);
    } catch (const InputError&) {
        throw InputError(fmt::format("--method {}: must be auto, hemicube or raycast", text));
    }
    o.method_auto = false;
}

RowOptions resolve_row_method(const RowOptions& o, const Scene& drawn) {
    RowOptions r = o;
    if (!o.method_auto) return r;
    r.method_auto = false;
    const bool obstructions = drawn.obstruction_first < drawn.patches.size();
    const std::size_t pieces = drawn.grids.size(), patches = drawn.patches.size();
    // The rays a ray-cast scene's rows would cast: --rays, else --fine-row-rays or its default,
    // refined to the tolerance unless --rays fixes the count.
    const std::uint64_t rays = o.rays_given ? o.rays : o.fine_row_rays ? o.fine_row_rays : default_fine_row_rays(o.resolution);
    if (!o.cost_model.builtin()) {
        // A measured cost model (--cost-model): the cheaper engine for this mesh's typical row.
        const SceneFacts facts = scene_facts(drawn, o.resolution, o.cost_model);
        const MethodCosts c = scene_method_costs(facts, expected_row_rays(rays_refined(o) ? o.tolerance : 0.0, rays));
        r.auto_raycast = c.rays_cheaper() && !obstructions && o.fine_rows != FineRows::hemicubes;
        r.method_costs = c;
        r.method_choice = fmt::format(
            "auto by {}: a row of {} hemicube{} ({} pieces, N = {}) {:.3g} ms against rays {:.3g} ms{}", o.cost_model.source,
            c.hemicubes, c.hemicubes == 1 ? "" : "s", pieces, o.resolution, 1e-6 * c.hemicube_ns, 1e-6 * c.rays_ns,
            !c.rays_cheaper()   ? ""
            : obstructions      ? ", but obstruction-only surfaces"
            : !r.auto_raycast   ? ", but --fine-rows hemicubes"
                                : "");
    } else {
        const bool mesh = rays_preferred(pieces, patches);
        r.auto_raycast = mesh && !obstructions && o.fine_rows != FineRows::hemicubes;
        const auto why_mesh = [&] {
            return pieces >= kFineRowsByRaysMinPieces
                       ? fmt::format(", {} or more", kFineRowsByRaysMinPieces)
                       : fmt::format(" of {} patches, {} or more of at most {} patches each", patches,
                                     kRaysMinMeshPieces, kRaysMaxPatchesPerPiece);
        };
        r.method_choice = fmt::format("auto: {} pieces{}", pieces,
                                      !mesh ? fmt::format(" of {} patches: rays need {} pieces, or {} of at most {} patches each",
                                                          patches, kFineRowsByRaysMinPieces,
                                                          kRaysMinMeshPieces,
                                                          kRaysMaxPatchesPerPiece)
                                      : obstructions    ? ", obstruction-only surfaces"
                                      : !r.auto_raycast ? ", --fine-rows hemicubes"
                                                        : why_mesh());
    }
    r.method = r.auto_raycast ? RowMethod::Raycast : RowMethod::Hemicube;
    if (r.auto_raycast && !o.rays_given) r.rays = rays;
    return r;
}

std::string_view to_string(RowMethod m) { return m == RowMethod::Raycast ? "raycast" : "hemicube"; }
std::string_view to_string(Correction c) { return c == Correction::Near ? "near" : "none"; }
std::string_view to_string(FarFieldMode f) {
    switch (f) {
        case FarFieldMode::on: return "on";
        case FarFieldMode::off: return "off";
        case FarFieldMode::automatic: break;
    }
    return "auto";
}
std::string_view to_string(EnforceRequest e) {
    switch (e) {
        case EnforceRequest::Reciprocity: return "reciprocity";
        case EnforceRequest::Closure: return "closure";
        case EnforceRequest::Both: return "both";
        case EnforceRequest::None: break;
    }
    return "";
}

void validate(const SceneOptions& o) {
    if (o.max_patch_edge > 0 && o.patches > 0)
        throw InputError("--max-patch-edge and --patches: give one of the two");
    if (o.max_patch_edge < 0 || !std::isfinite(o.max_patch_edge))
        throw InputError(fmt::format("--max-patch-edge {}: must be a finite length > 0", o.max_patch_edge));
    if (!o.subdivide && (o.max_patch_edge > 0 || o.patches > 0))
        throw InputError("--no-subdivide keeps every face as one patch: give neither --max-patch-edge nor --patches with it");
    if (!o.subdivide && o.contact_cuts == ContactCuts::On)
        throw InputError("--contact-cuts on with --no-subdivide: the cut faces are not one patch each (docs/adaptive.md)");
}

void validate(const RowOptions& o) {
    if (o.method == RowMethod::Hemicube || o.method_auto) check_row_resolution(o.resolution);
    if ((o.method == RowMethod::Raycast || o.rays_given) && o.rays == 0)
        throw InputError("--rays 0: at least 1 ray per patch");
    if ((o.tolerance != 0 || o.tolerance_given) && !(o.tolerance >= kMinTolerance && o.tolerance < 1.0))
        throw InputError(fmt::format("--tolerance {}: must be a number from {} (what double precision can honour in a "
                                     "row's sum) to below 1",
                                     o.tolerance, kMinTolerance));
    if (!(o.near_k > 0) || !std::isfinite(o.near_k))
        throw InputError(fmt::format("--near-k {}: must be a finite number > 0", o.near_k));
    if (!(o.near_min_ff >= 0 && o.near_min_ff <= 1))
        throw InputError(fmt::format("--near-min-ff {}: must be a number from 0 to 1 (a form factor)", o.near_min_ff));
    if (!(o.sub_hemicube_k >= 0) || !std::isfinite(o.sub_hemicube_k))
        throw InputError(fmt::format("--sub-hemicube-k {}: must be a finite number >= 0", o.sub_hemicube_k));
    if (o.exact_visibility_occluders > kMaxExactVisibilityOccluders)
        throw InputError(fmt::format("--exact-visibility {}: must be within 0..{} (possible occluders in a near pair's shaft; 0: off)",
                                     o.exact_visibility_occluders, kMaxExactVisibilityOccluders));
    check_cost_model(o.cost_model, o.cost_model.builtin() ? "the built-in cost model" : "--cost-model " + o.cost_model.source);
}

HemicubeOptions hemicube_options(const RowOptions& o) {
    HemicubeOptions h;
    h.resolution = o.resolution;
    h.backend = o.backend;
    h.threads = o.threads;
    h.rotate = o.rotate;
    h.seed = o.seed;
    h.worker_processes = o.worker_processes;
    h.occlusion_culling = o.occlusion_culling;
    h.enclosure_without_depth = o.enclosure_without_depth;
    return h;
}

bool rays_refined(const RowOptions& o) { return o.tolerance > 0 && !o.rays_given; }

RaycastOptions raycast_options(const RowOptions& o) {
    RaycastOptions r;
    r.rays = o.rays;
    r.tolerance = rays_refined(o) ? o.tolerance : 0.0;
    r.threads = o.threads;
    r.seed = o.seed;
    return r;
}

NearFieldOptions near_field_options(const RowOptions& o) {
    if (o.method == RowMethod::Raycast) {
        // The ray caster samples the whole sender (no sender quadrature); its noise, for the
        // per-row error estimate. No far field: its rows carry no pixel error to remove.
        NearFieldOptions nf;
        nf.k = o.near_k;
        // Rows refined to a tolerance measure their own noise (RowStages::measured): none modelled.
        nf.rays = rays_refined(o) ? 0.0 : static_cast<double>(o.rays);
        nf.min_near_value = o.near_min_ff;
        nf.obstruction_receivers = false;  // it credits either side of an obstruction (raycast_provider.cpp)
        nf.exact_visibility_occluders = o.exact_visibility_auto ? 0 : o.exact_visibility_occluders;
        return nf;
    }
    NearFieldOptions nf =
        near_field_options_for_hemicube(o.resolution, o.near_k, o.cost_model.pixel_ns, o.cost_model.cpu_scale);
    nf.far_field = o.far_field;
    nf.far_field_emitters = o.far_field_emitters;
    nf.sub_hemicube_k = o.sub_hemicube_k;
    nf.exact_visibility_occluders = o.exact_visibility_occluders;
    if (o.exact_visibility_auto) {
        nf.exact_visibility_occluders = kAutoExactVisibilityOccluders;
        nf.exact_visibility_budget =
            exact_visibility_budget_for_hemicube(o.resolution, o.cost_model.pixel_ns, o.cost_model.cpu_scale);
    }
    return nf;
}

EnforceMode enforce_mode(EnforceRequest e) {
    FFCUBE_CHECK(e != EnforceRequest::None);
    return e == EnforceRequest::Reciprocity ? EnforceMode::Reciprocity : EnforceMode::Closure;
}

}  // namespace ffcube
