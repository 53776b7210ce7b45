// Render checkpoints: the film's accumulators and sample count, written atomically (temporary file +
// rename) with a checksum, and keyed by everything that decides the pixels, so a render resumed from
// any checkpoint gives exactly the pixels of an uninterrupted one.
#pragma once
#include <cstdint>
#include <string>

#include "runtime/renderer.h"  // and through it kernels/shared/light_types.h

// A hash of the scene content (the header and every device array but the BVH layouts: geometry in the
// tree's leaf order, materials, lights, textures, camera) and of the settings that change pixels (spp,
// max_depth, seed, Russian roulette depth, sampler, and the integrator where it is not `path`). The device
// set is not in it, nor the layouts built for it: a checkpoint written on some devices resumes on any others.
uint64_t render_key(const DeviceScene& scene, const RenderOptions& options);

// The film's layers (Film::words, with the layout's names) and sample count. RuntimeFailure on I/O errors.
void write_checkpoint(const std::string& path, uint64_t key, const Film& film);

// UsageError naming the file when it is not a checkpoint, is damaged, or belongs to another scene,
// other settings, another technique, another film size or other layers (AOVs). Gives a Film with its
// layers and spp, not developed (what RenderOptions::resume needs). Checkpoints written before film
// layouts (PCLCKPT1: the path integrator's accumulators or the splat film alone) resume as they are:
// their bytes are those layers' words; with AOVs asked for they are refused, saying why.
Film read_checkpoint(const std::string& path, uint64_t key, uint32_t width, uint32_t height, const Technique& technique,
                     const FilmLayout& layout);
// The same for a render of `scene` with `options`: its technique, AOVs and options.checkpoint_key.
Film read_checkpoint(const std::string& path, const DeviceScene& scene, const RenderOptions& options);
