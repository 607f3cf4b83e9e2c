/* A garment driven through the C API (garment_scenario.c, compiled as C11), and the mesh it
 * uses, for the test that compares it with the same scenario through the C++ API. */
#ifndef DRAPE_TESTS_GARMENT_SCENARIO_H_
#define DRAPE_TESTS_GARMENT_SCENARIO_H_

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

enum { kScenarioSegments = 40, kScenarioRings = 16 };
enum { kScenarioParticles = kScenarioSegments * (kScenarioRings + 1) };
enum { kScenarioTriangles = 2 * kScenarioSegments * kScenarioRings };

/* A skirt (a tube, segments around, rings down) hanging from a waistband of `radius` metres
 * centred on `top`, `length` metres long: positions (3 per particle, ring by ring) and
 * triangles (3 indices each). */
void scenario_skirt_mesh(const float top[3], float radius, float length, float* positions,
                         uint32_t* triangles);

/* Loads `asset_path`, skins the skirt to the root joint (waistband exactly, the rest within
 * 15 cm), then steps `frames` frames of 1/60 s of the asset's first clip against its baked
 * colliders and two engine shapes (a floor and a swinging capsule), 2 substeps. Writes the final
 * positions (kScenarioParticles * 3 floats), the contacts and the springs beyond the strain limit
 * of the last frame. Returns 0, or the drape_status of the first failing call (its message in
 * drape_last_error()). */
int scenario_run(const char* asset_path, int frames, float* out_positions, uint32_t* out_contacts,
                 uint32_t* out_overstretched);

/* The capsule's transform at a frame (12 floats), shared by both scenarios. */
void scenario_staff(const float root[12], int frame, float out[12]);

#ifdef __cplusplus
}
#endif

#endif /* DRAPE_TESTS_GARMENT_SCENARIO_H_ */
