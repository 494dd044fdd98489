// The photon-map importer (core/photon/photon_map_io.h), as PUT /v1/photon-maps/<key> and the
// daemon's photon-map cache call it: deserialize_photon_maps with any key, and
// read_photon_map_key.
//
// A file ends with the SHA-256 of everything before it, which random mutations never match, so
// the checks behind it (key, statistics, photon counts, the kd-tree's structure) would go
// untested. The first input byte therefore chooses: odd, the rest of the input is the file
// without its checksum and the fuzzer appends the right one; even, the rest is taken as it is
// (fuzz/corpus/photon_map holds both kinds, made from files the daemon wrote).
#include <cstdint>
#include <span>
#include <vector>

#include "core/photon/photon_map_io.h"
#include "fuzz/checksummed_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size == 0) return 0;
    const std::vector<uint8_t> bytes = photond::fuzz::checksummed_file(data, size);
    (void)photond::read_photon_map_key(bytes);
    const photond::Expected<photond::PhotonMaps> maps =
        photond::deserialize_photon_maps(bytes, std::string());
    photond::fuzz::require(maps || !maps.error().message.empty(), "refused with an empty message");
    if (maps) {
        // What was accepted is written back identically (the file holds the tree's order).
        const auto again =
            photond::serialize_photon_maps(*maps, photond::read_photon_map_key(bytes));
        photond::fuzz::require(again && *again == bytes,
                               "an accepted file is not written back byte for byte");
    }
    return 0;
}
