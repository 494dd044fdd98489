// A camera sample's radiance split by how its light arrived: the AOV layers emission, direct,
// indirect and caustic. The total is accumulated term by term exactly as a plain Color would be,
// so the beauty pass does not change by a bit when the parts are kept beside it; the parts sum to
// the total up to rounding.
#pragma once

#include "core/math/vec.h"

namespace photond {

struct RadianceParts {
    Color total{0.0f};
    Color emission{0.0f};  // emitters and the sky seen from the camera, also through ideal specular surfaces
    Color direct{0.0f};    // light sampling at the visible surface (and the emitters its MIS partners hit)
    Color indirect{0.0f};  // light after one or more diffuse or glossy bounces (final gathering)
    Color caustic{0.0f};   // light focused onto the visible surface by ideal specular surfaces

    void add_emission(const Color& c) { add(c, &RadianceParts::emission); }
    void add_direct(const Color& c) { add(c, &RadianceParts::direct); }
    void add_indirect(const Color& c) { add(c, &RadianceParts::indirect); }
    void add_caustic(const Color& c) { add(c, &RadianceParts::caustic); }
    void add(const Color& c, Color RadianceParts::*part) {
        total += c;
        this->*part += c;
    }

    RadianceParts& operator+=(const RadianceParts& o) {
        total += o.total;
        emission += o.emission;
        direct += o.direct;
        indirect += o.indirect;
        caustic += o.caustic;
        return *this;
    }
    /// Every part seen through a filter (a specular bounce's weight, a medium's transmittance).
    friend RadianceParts operator*(const Color& w, const RadianceParts& p) {
        return {w * p.total, w * p.emission, w * p.direct, w * p.indirect, w * p.caustic};
    }
    friend RadianceParts operator*(const RadianceParts& p, float s) {
        return {p.total * s, p.emission * s, p.direct * s, p.indirect * s, p.caustic * s};
    }
};

}  // namespace photond
