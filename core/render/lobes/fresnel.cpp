// The exact Fresnel terms of Fresnel::eval, out of line: the inline part of eval keeps the common Schlick and One
// modes in every lobe, and these longer closed forms stay one call away.
#include "core/render/lobes/fresnel.h"

namespace specula {

Color3 Fresnel::evalExact(float cosThetaD) const {
    switch (mode) {
        case Mode::Dielectric: return Color3(fresnelDielectric(cosThetaD, eta));
        case Mode::Conductor:
            return {fresnelConductor(cosThetaD, etaC.x, kC.x), fresnelConductor(cosThetaD, etaC.y, kC.y),
                    fresnelConductor(cosThetaD, etaC.z, kC.z)};
        case Mode::One: return Color3(1.f);
        case Mode::Schlick: return fresnelSchlick(cosThetaD, f0);
    }
    return Color3(1.f);
}

}  // namespace specula
