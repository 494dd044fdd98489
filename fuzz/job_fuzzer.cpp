// The job description reader: the text of a POST /v1/jobs body or of `photond render --job FILE`
// through protocol::parse_job_text_detailed (protocol/job.h), which checks the nesting, parses
// the JSON (with the line/column message when it is malformed) and validates every field.
//
// Beyond "no crash", two properties: a refusal always names what is wrong (a non-empty message),
// and an accepted job survives to_json and parse_job unchanged (protocol/job.h promises
// parse_job(to_json(job)) == job). A broken property aborts, which libFuzzer reports as a crash.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>
#include <variant>

#include "protocol/job.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace photond::protocol;
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    const std::variant<Job, FieldError> parsed = parse_job_text_detailed(text);
    if (const auto* error = std::get_if<FieldError>(&parsed)) {
        if (error->message.empty()) {
            std::fprintf(stderr, "refused with an empty message (path '%s')\n",
                         error->path.c_str());
            std::abort();
        }
        return 0;
    }
    const Job& job = std::get<Job>(parsed);
    const nlohmann::json written = to_json(job);
    const auto again = parse_job(written);
    if (!again) {
        std::fprintf(stderr, "to_json's document is refused: %s\n%s\n",
                     again.error().message.c_str(), written.dump().c_str());
        std::abort();
    }
    if (!(*again == job)) {
        std::fprintf(stderr, "to_json and parse_job changed the job:\n%s\n%s\n",
                     written.dump().c_str(), to_json(*again).dump().c_str());
        std::abort();
    }
    return 0;
}
