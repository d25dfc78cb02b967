// cull.comp -- the culling (and LOD choice) pass for GL >= 4.3: compute
// shaders compact the visible instances and write the indirect draw
// commands themselves, so the CPU never waits for a count (docs/culling.md).
// The same bound and LOD choice as cull.vert (cull.glsl); the same output:
// the kept records byte for byte, in their original order, each followed by
// its original index (int) and tint (3 floats), level after level.
//
// Four dispatches of this file (AXIAL_CULL_STAGE 1 to 4), an order-keeping
// compaction (a prefix sum; no atomics, no work-group barriers on the
// per-instance stages):
//   1. classify: one invocation per instance: its level, or culled.
//   2. rank: one invocation per block of 256 instances walks them in order:
//      each kept one's rank among the block's instances of its level, and
//      the block's count per level.
//   3. offsets: ONE work group scans the blocks' counts: where each block's
//      run of each level starts, the total per level, and the indirect
//      draw commands (instanceCount and baseInstance of each slot's level).
//   4. scatter: one invocation per instance copies a kept record to its place.
#include "axial.glsl"
#include "quantized.glsl"
#include "bounds.glsl"
#include "cull.glsl"

#define AXIAL_BLOCK 256u     // instances per block of the rank stage
#define AXIAL_SCAN 256u      // invocations of the offsets stage
#define AXIAL_LOCAL 64       // invocations per work group of the other stages
#define AXIAL_CULLED_OUT 0xFFFFFFFFu

uniform uint u_count;         // instances
uniform uint u_blocks;        // blocks: ceil(u_count / AXIAL_BLOCK)
uniform uint u_slots;         // indirect draw commands to fill

layout(std430, binding = 0) readonly buffer Records { uint rec_in[]; };      // AXIAL_REC_WORDS words an instance
layout(std430, binding = 1) readonly buffer Tints { uint tint_in[]; };       // 3 floats an instance (AXIAL_TINT_WORDS 3)
layout(std430, binding = 2) buffer Info { uint info[]; };                    // level, then level << 16 | rank; or AXIAL_CULLED_OUT
layout(std430, binding = 3) buffer BlockCounts { uvec4 block_count[]; };     // per block: kept instances per level
layout(std430, binding = 4) buffer BlockOffsets { uvec4 block_off[]; };      // per block: first output record per level
layout(std430, binding = 5) writeonly buffer Out { uint rec_out[]; };        // the compacted records
layout(std430, binding = 6) buffer Counts { uvec4 level_count; uvec4 level_first; };
layout(std430, binding = 7) buffer Commands { uint cmd[]; };                 // DrawElementsIndirectCommand, 5 uints each
layout(std430, binding = 8) readonly buffer SlotLevels { uint slot_level[]; };

#define AXIAL_OUT_WORDS (AXIAL_REC_WORDS + 1 + AXIAL_TINT_WORDS)

// This invocation's index along a 1D or 2D grid of work groups (more than
// 65 535 groups along x go on y; the extra ones of the last row do nothing).
uint axial_invocation() {
    return (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * uint(AXIAL_LOCAL) + gl_LocalInvocationID.x;
}

#if AXIAL_CULL_STAGE == 1
layout(local_size_x = AXIAL_LOCAL) in;

float axial_word(uint base, uint k) {
    return uintBitsToFloat(rec_in[base + k]);
}

AxialInstance axial_record(uint i) {
    uint b = i * uint(AXIAL_REC_WORDS);
#ifdef AXIAL_QUANTIZED
    uvec4 q0 = uvec4(rec_in[b] & 0xFFFFu, rec_in[b] >> 16u, rec_in[b + 1u] & 0xFFFFu, rec_in[b + 1u] >> 16u);
    uvec4 q1 = uvec4(rec_in[b + 2u] & 0xFFFFu, rec_in[b + 2u] >> 16u, rec_in[b + 3u] & 0xFFFFu, rec_in[b + 3u] >> 16u);
    uvec4 q2 = uvec4(rec_in[b + 4u] & 0xFFFFu, rec_in[b + 4u] >> 16u, rec_in[b + 5u] & 0xFFFFu, rec_in[b + 5u] >> 16u);
    uvec4 q3 = uvec4(rec_in[b + 6u] & 0xFFFFu, rec_in[b + 6u] >> 16u, rec_in[b + 7u] & 0xFFFFu, rec_in[b + 7u] >> 16u);
#ifdef AXIAL_EXTENDED
    uvec3 q4 = uvec3(rec_in[b + 8u] & 0xFFFFu, rec_in[b + 8u] >> 16u, rec_in[b + 9u] & 0xFFFFu);
#else
    uvec3 q4 = uvec3(0u);
#endif
    return axial_dequantize(q0, q1, q2, q3, q4);
#else
    vec4 d12 = vec4(axial_word(b, 0u), axial_word(b, 1u), axial_word(b, 2u), axial_word(b, 3u));
    vec4 d34 = vec4(axial_word(b, 4u), axial_word(b, 5u), axial_word(b, 6u), axial_word(b, 7u));
    vec2 d5 = vec2(axial_word(b, 8u), axial_word(b, 9u));
    vec3 position = vec3(axial_word(b, 10u), axial_word(b, 11u), axial_word(b, 12u));
    vec3 angles = vec3(axial_word(b, 13u), axial_word(b, 14u), axial_word(b, 15u));
#ifdef AXIAL_EXTENDED
    return AxialInstance(d12, d34, d5, position, angles, axial_word(b, 16u), axial_word(b, 17u), axial_word(b, 18u));
#else
    return axial_instance(d12, d34, d5, position, angles);
#endif
#endif
}

void main() {
    uint i = axial_invocation();
    if (i >= u_count) return;
    int level = axial_cull_level(axial_record(i));
    info[i] = level < 0 ? AXIAL_CULLED_OUT : uint(level);
}
#endif

#if AXIAL_CULL_STAGE == 2
layout(local_size_x = AXIAL_LOCAL) in;

void main() {
    uint block = axial_invocation();
    if (block >= u_blocks) return;
    uvec4 count = uvec4(0u);
    uint end = min((block + 1u) * AXIAL_BLOCK, u_count);
    for (uint i = block * AXIAL_BLOCK; i < end; ++i) {
        uint level = info[i];
        if (level == AXIAL_CULLED_OUT) continue;
        info[i] = (level << 16u) | count[level];
        count[level] += 1u;
    }
    block_count[block] = count;
}
#endif

#if AXIAL_CULL_STAGE == 3
layout(local_size_x = 256) in;
shared uvec4 s_sum[AXIAL_SCAN];

void main() {
    uint lid = gl_LocalInvocationID.x;
    uint per = (u_blocks + AXIAL_SCAN - 1u) / AXIAL_SCAN;
    uint b0 = min(lid * per, u_blocks);
    uint b1 = min(b0 + per, u_blocks);
    uvec4 mine = uvec4(0u);
    for (uint b = b0; b < b1; ++b) mine += block_count[b];
    s_sum[lid] = mine;
    barrier();
    for (uint step = 1u; step < AXIAL_SCAN; step <<= 1u) {  // inclusive scan of the invocations' sums
        uvec4 add = lid >= step ? s_sum[lid - step] : uvec4(0u);
        barrier();
        s_sum[lid] += add;
        barrier();
    }
    uvec4 total = s_sum[AXIAL_SCAN - 1u];
    uvec4 first = uvec4(0u, total.x, total.x + total.y, total.x + total.y + total.z);  // levels one after another
    uvec4 running = first + s_sum[lid] - mine;
    for (uint b = b0; b < b1; ++b) {
        block_off[b] = running;
        running += block_count[b];
    }
    if (lid == 0u) {
        level_count = total;
        level_first = first;
        for (uint s = 0u; s < u_slots; ++s) {
            uint level = slot_level[s];
            cmd[5u * s + 1u] = total[level];  // instanceCount
            cmd[5u * s + 4u] = first[level];  // baseInstance: the level's run of records
        }
    }
}
#endif

#if AXIAL_CULL_STAGE == 4
layout(local_size_x = AXIAL_LOCAL) in;

void main() {
    uint i = axial_invocation();
    if (i >= u_count) return;
    uint code = info[i];
    if (code == AXIAL_CULLED_OUT) return;
    uint dst = (block_off[i / AXIAL_BLOCK][code >> 16u] + (code & 0xFFFFu)) * uint(AXIAL_OUT_WORDS);
    uint src = i * uint(AXIAL_REC_WORDS);
    for (uint k = 0u; k < uint(AXIAL_REC_WORDS); ++k) rec_out[dst + k] = rec_in[src + k];
    rec_out[dst + uint(AXIAL_REC_WORDS)] = i;  // the original index (an int: i < 2^31)
#if AXIAL_TINT_WORDS > 0
    for (uint k = 0u; k < 3u; ++k) rec_out[dst + uint(AXIAL_REC_WORDS) + 1u + k] = tint_in[3u * i + k];
#endif
}
#endif
