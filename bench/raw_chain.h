// A hand-written AVX2 dependent-fetch loop: the reference point of BM_SampleChain
// (bench/raw_chain_avx2.cpp).
#pragma once

#include "texture/padded_texels.h"

namespace reliefsim::bench {

/// Whether this build has the AVX2 loop (x86-64 with GCC or Clang); the CPU must also
/// run AVX2 and FMA.
bool RawChainAvx2Available();

/// `chain` dependent bilinear fetches (power-of-two repeat) for each of n lanes from
/// (u[i], v[i]), `packs` packs of 8 lanes interleaved; returns a checksum. Needs a
/// power-of-two texture padded for repeat.
float RawChainAvx2(const PaddedTexels& tex, const float* u, const float* v, int n,
                   int chain, int packs);

}  // namespace reliefsim::bench
