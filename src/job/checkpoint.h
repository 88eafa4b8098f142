// Checkpoints of a render: every film accumulator and the integrator's own
// state between passes (mlt: chains and b), with a header saying which
// render they belong to and how far it got. Written atomically (temporary
// file, fsync, rename); read back only after the magic, the sizes and a
// checksum of the whole payload check out.
//
// Exact splitting: a render split into pass ranges [A, B) (gradus --passes)
// gives partial checkpoints that MergeCheckpoints sums into the checkpoint of
// passes [0, N); resuming it renders nothing more and finishes the image.
// The sums differ from the single-process ones only in the order of the
// double-precision additions.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace gradus {

struct Checkpoint {
    // What makes two renders the same render: scene files' hash, camera,
    // sampler, filter, resolution, crop, integrator and its parameters, the
    // target spp and the seed (text, compared for equality).
    std::string identity;
    std::string integrator;
    uint64_t seed = 0;
    int passBegin = 0, passEnd = 0;  // passes [passBegin, passEnd) are accumulated
    int sppBegin = 0, sppEnd = 0;    // their pixel samples [sppBegin, sppEnd)
    bool complete = false;           // the render's last pass is included
    double seconds = 0;              // render seconds spent so far (all sessions)
    uint64_t nonFinite = 0;
    std::string film;                // Film::saveState()
    std::string state;               // Integrator::saveState()
};

// Atomic write: FILE.tmp, fsync, rename, fsync of the directory. Throws Error.
void WriteCheckpoint(const std::string &path, const Checkpoint &c);
// Throws Error ("file: ...") for a missing, truncated, corrupted or foreign file.
Checkpoint ReadCheckpoint(const std::string &path);
// Sums partial checkpoints of one render whose pass ranges are disjoint and
// together cover [0, N) (any order); throws Error naming the offending file.
Checkpoint MergeCheckpoints(const std::vector<Checkpoint> &parts, const std::vector<std::string> &names);
// One line per field, for imgtool info.
std::string DescribeCheckpoint(const Checkpoint &c);
// True when the file starts with the checkpoint magic.
bool IsCheckpointFile(const std::string &path);

}  // namespace gradus
