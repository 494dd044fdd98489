#include "clients/job_view.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

namespace photond::client {
namespace {

using nlohmann::json;

const json* member(const json& object, const char* name) {
    if (!object.is_object()) return nullptr;
    const auto it = object.find(name);
    return it == object.end() || it->is_null() ? nullptr : &*it;
}

// A member of the status document, or of its "job" description when the status nests it.
const json* job_member(const json& status, const char* name) {
    if (const json* value = member(status, name)) return value;
    if (const json* job = member(status, "job")) return member(*job, name);
    return nullptr;
}

std::string text(const json& value) {
    return value.is_string() ? value.get<std::string>() : value.dump();
}

std::string seconds_text(const json& value) {
    if (!value.is_number()) return text(value);
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.2f s", value.get<double>());
    return buffer;
}

std::string percent_text(double fraction) {
    char buffer[16];
    std::snprintf(buffer, sizeof buffer, "%3d%%",
                  static_cast<int>(std::floor(std::clamp(fraction, 0.0, 1.0) * 100.0)));
    return buffer;
}

std::string progress_text(const JobProgress& progress) {
    std::string result = std::to_string(progress.tiles_done) + "/" +
                         std::to_string(progress.tiles_total) + " tiles (";
    std::string percent = percent_text(progress.fraction);
    percent.erase(0, percent.find_first_not_of(' '));
    return result + percent + ")";
}

std::string timings_text(const json& timings) {
    std::vector<std::string> items;
    if (timings.is_object()) {
        // JSON objects lose the order the passes ran in: restore it for the known passes.
        static constexpr std::array<std::string_view, 8> kPassOrder{
            "scene",  "acceleration", "photon_tracing", "photon_kdtree", "irradiance_cache",
            "render", "writing",      "total"};
        std::vector<std::pair<size_t, std::string>> ordered;
        for (const auto& [name, value] : timings.items()) {
            const size_t rank = static_cast<size_t>(
                std::find(kPassOrder.begin(), kPassOrder.end(), name) - kPassOrder.begin());
            ordered.emplace_back(rank, name + " " + seconds_text(value));
        }
        std::stable_sort(ordered.begin(), ordered.end(),
                         [](const auto& a, const auto& b) { return a.first < b.first; });
        for (auto& item : ordered) items.push_back(std::move(item.second));
    } else if (timings.is_array()) {
        for (const json& entry : timings) {
            const json* name = member(entry, "name");
            const json* seconds = member(entry, "seconds");
            if (name && seconds)
                items.push_back(text(*name) + " " + seconds_text(*seconds));
            else
                items.push_back(text(entry));
        }
    } else {
        return text(timings);
    }
    std::string result;
    for (const std::string& item : items) result += (result.empty() ? "" : ", ") + item;
    return result;
}

std::vector<std::string> plan_lines(const json& plan) {
    const json* decisions = &plan;
    if (plan.is_object()) {
        if (const json* passes = member(plan, "passes"))
            decisions = passes;
        else if (const json* list = member(plan, "decisions"))
            decisions = list;
    }
    std::vector<std::string> lines;
    if (!decisions->is_array()) return {text(plan)};
    for (const json& decision : *decisions) {
        const json* pass = member(decision, "pass");
        if (!pass) pass = member(decision, "name");
        if (!pass) {
            lines.push_back(text(decision));
            continue;
        }
        std::string line = text(*pass);
        if (const json* enabled = member(decision, "enabled"); enabled && enabled->is_boolean())
            line += enabled->get<bool>() ? ": yes" : ": skipped";
        if (const json* reason = member(decision, "reason")) line += " (" + text(*reason) + ")";
        lines.push_back(line);
    }
    return lines;
}

const json* photons_of(const json& status) {
    if (const json* photons = member(status, "photons"); photons && photons->is_object())
        return photons;
    if (const json* statistics = member(status, "statistics"))
        if (const json* photons = member(*statistics, "photons"); photons && photons->is_object())
            return photons;
    return nullptr;
}

}  // namespace

std::string job_state(const json& status) {
    const json* state = member(status, "state");
    return state && state->is_string() ? state->get<std::string>() : std::string();
}

bool is_terminal_state(std::string_view state) {
    return state == "done" || state == "failed" || state == "cancelled" || state == "canceled";
}

std::optional<JobProgress> read_progress(const json& document) {
    const json* source = member(document, "progress");
    if (!source || !source->is_object()) source = &document;
    const json* done = member(*source, "tiles_done");
    const json* total = member(*source, "tiles_total");
    const json* fraction = member(*source, "fraction");
    if (!(done && done->is_number()) && !(fraction && fraction->is_number())) return std::nullopt;
    JobProgress progress;
    if (done && done->is_number()) progress.tiles_done = done->get<int64_t>();
    if (total && total->is_number()) progress.tiles_total = total->get<int64_t>();
    if (fraction && fraction->is_number()) {
        progress.fraction = fraction->get<double>();
    } else if (progress.tiles_total > 0) {
        progress.fraction = double(progress.tiles_done) / double(progress.tiles_total);
    }
    progress.fraction = std::clamp(progress.fraction, 0.0, 1.0);
    return progress;
}

std::string describe_scene(const json& scene) {
    if (!scene.is_object()) return text(scene);
    if (const json* name = member(scene, "builtin")) return "builtin:" + text(*name);
    if (const json* path = member(scene, "path")) return "path:" + text(*path);
    if (const json* id = member(scene, "id")) return text(*id);
    return scene.dump();
}

std::string describe_job_error(const json& error) {
    if (error.is_string()) return error.get<std::string>();
    if (!error.is_object()) return error.dump();
    const json* title = member(error, "title");
    const json* detail = member(error, "detail");
    const json* message = member(error, "message");
    std::string result;
    if (title) result = text(*title);
    if (detail) result += (result.empty() ? "" : ": ") + text(*detail);
    if (result.empty() && message) result = text(*message);
    if (result.empty()) return error.dump();
    if (const json* field = member(error, "field")) result += " (field: " + text(*field) + ")";
    return result;
}

std::string format_status(const json& status) {
    std::vector<std::pair<std::string, std::string>> rows;
    auto add = [&](std::string name, std::string value) {
        rows.emplace_back(std::move(name), std::move(value));
    };
    if (const json* id = member(status, "id")) add("job", text(*id));
    if (const json* state = member(status, "state")) {
        std::string value = text(*state);
        if (const json* pass = member(status, "pass")) value += " (" + text(*pass) + ")";
        add("state", value);
    }
    if (const json* scene = job_member(status, "scene")) add("scene", describe_scene(*scene));
    if (const json* preset = job_member(status, "preset")) add("preset", text(*preset));
    if (const json* integrator = job_member(status, "integrator"))
        add("integrator", text(*integrator));
    if (const json* image = job_member(status, "image"); image && image->is_object()) {
        std::string value;
        const json* width = member(*image, "width");
        const json* height = member(*image, "height");
        if (width && height) value = text(*width) + "x" + text(*height);
        if (const json* spp = member(*image, "spp"))
            value += (value.empty() ? "" : ", ") + text(*spp) + " spp";
        if (!value.empty()) add("image", value);
    }
    if (const json* priority = job_member(status, "priority")) add("priority", text(*priority));
    if (const std::optional<JobProgress> progress = read_progress(status))
        add("progress", progress_text(*progress));
    if (const json* photons = photons_of(status)) {
        std::string value;
        if (const json* cache = member(*photons, "cache")) value = "cache " + text(*cache);
        if (const json* key = member(*photons, "key"))
            value += (value.empty() ? "" : ", ") + std::string("key ") + text(*key);
        if (!value.empty()) add("photons", value);
    }
    if (const json* timings = member(status, "timings")) add("timings", timings_text(*timings));
    for (const char* time : {"created_at", "started_at", "finished_at"})
        if (const json* value = member(status, time)) add(time, text(*value));
    if (const json* plan = member(status, "plan")) {
        bool first = true;
        for (std::string& line : plan_lines(*plan)) {
            add(first ? "plan" : "", std::move(line));
            first = false;
        }
    }
    if (const json* error = member(status, "error")) add("error", describe_job_error(*error));

    size_t name_width = 0;
    for (const auto& row : rows) name_width = std::max(name_width, row.first.size());
    std::string result;
    for (const auto& [name, value] : rows) {
        result += name + std::string(name_width + 2 - name.size(), ' ') + value + "\n";
    }
    return result;
}

std::string format_job_list(const json& jobs) {
    if (!jobs.is_array() || jobs.empty()) return "no jobs\n";
    std::vector<std::array<std::string, 4>> table{{"ID", "STATE", "PROGRESS", "SCENE"}};
    for (const json& status : jobs) {
        std::array<std::string, 4> row;
        if (const json* id = member(status, "id")) row[0] = text(*id);
        row[1] = job_state(status);
        if (const std::optional<JobProgress> progress = read_progress(status)) {
            row[2] = percent_text(progress->fraction);
            row[2].erase(0, row[2].find_first_not_of(' '));
        }
        if (const json* scene = job_member(status, "scene")) row[3] = describe_scene(*scene);
        table.push_back(std::move(row));
    }
    std::array<size_t, 4> widths{};
    for (const auto& row : table)
        for (size_t c = 0; c < row.size(); ++c) widths[c] = std::max(widths[c], row[c].size());
    std::string result;
    for (const auto& row : table) {
        std::string line;
        for (size_t c = 0; c < row.size(); ++c) {
            line += row[c];
            if (c + 1 < row.size()) line += std::string(widths[c] + 2 - row[c].size(), ' ');
        }
        while (!line.empty() && line.back() == ' ') line.pop_back();
        result += line + "\n";
    }
    return result;
}

std::string progress_bar(const JobProgress& progress, int width) {
    const double fraction = std::clamp(progress.fraction, 0.0, 1.0);
    const int filled = std::clamp(static_cast<int>(std::floor(fraction * width)), 0, width);
    std::string bar;
    bar.reserve(static_cast<size_t>(width) + 40);
    bar.push_back('[');
    bar.append(static_cast<size_t>(filled), '#');
    bar.append(static_cast<size_t>(width - filled), '-');
    bar.append("] ");
    bar.append(percent_text(fraction));
    if (progress.tiles_total > 0) {
        bar.append("  ");
        bar.append(std::to_string(progress.tiles_done));
        bar.push_back('/');
        bar.append(std::to_string(progress.tiles_total));
        bar.append(" tiles");
    }
    return bar;
}

}  // namespace photond::client
