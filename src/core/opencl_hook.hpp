// The seam between the core and the OpenCL engine: src/cl implements these, or
// src/core/no_opencl.cpp when voxmesh is built without OpenCL.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace voxmesh::detail {

// Meshes with OpenCL devices (Backend::OpenCL) or devices plus CPU threads (Backend::Hybrid).
// Throws Error when no usable device exists (OpenCL); Hybrid then runs the CPU engine
// alone, with a warning.
// `storage`: a mesh whose arrays' capacity the result reuses (extract_into).
Mesh opencl_extract(const VolumeView& volume, const Options& options, Stats& stats, bool hybrid, Mesh storage = {});

// Every usable OpenCL device; empty when there is none (never throws for a missing platform).
std::vector<DeviceInfo> opencl_devices();
// Frees the buffers and pinned blocks the devices opened so far keep between calls (their
// programs stay); opens none. A device busy meshing keeps its own.
void opencl_release_memory();

// Test and benchmark hooks, defined only when the library is built with the OpenCL engine
// (then VOXMESH_HAS_OPENCL is defined for everything linking voxmesh).
#ifdef VOXMESH_HAS_OPENCL
// The scan kernel on device `device`: the exclusive prefix sums of `values`, followed by
// their total (values.size() + 1 entries). gpu_shape: launched as on GPUs (work-groups of
// up to 256 work-items, 8 elements each), also on a CPU device, where the engine launches a
// work-item of 1024 elements per work-group.
std::vector<std::uint32_t> opencl_exclusive_scan(const std::vector<std::uint32_t>& values, int device = 0,
                                                 bool gpu_shape = false);
// Presents each partitionable OpenCL device as (at most two) sub-devices of one compute
// unit each, or undoes that; list_devices() indices change. Not for use while meshing.
void opencl_split_devices(bool split);
// The bytes of buffers and pinned blocks the opened devices keep (0 before any is opened).
std::size_t opencl_kept_bytes();
// Treats every device as lacking cl_khr_fp64 (float interpolation, f64 volumes converted per
// chunk), so that the code path of most GPUs runs on PoCL too.
void opencl_pretend_no_fp64(bool pretend);
// Treats every device as not sharing host memory: samples are copied in and the mesh read
// back, the code path of discrete GPUs, on PoCL too.
void opencl_pretend_discrete(bool pretend);
// Builds the kernels as for a device that is not a CPU (without the CPU-only hints: row
// prefetches, the x86 lane-mask builtin) and launches the engine's scans in GPU work-groups,
// so that the kernel code GPUs compile runs on PoCL.
void opencl_pretend_gpu_build(bool pretend);
// Copies to and from discrete devices go through pinned blocks of this many bytes (0: the
// default), so that tests run many blocks through the double buffering.
void opencl_staging_block_bytes(std::size_t bytes);
// Makes every device spend this long more on each chunk it counts and on each piece it
// generates, and Hybrid's CPU worker on each chunk it counts and before it takes its first
// (0: off), so that the hand-over between a device and the CPU worker runs in tests whatever
// the machine.
void opencl_pretend_slow(double count_s, double generate_s, double cpu_count_s = 0, double cpu_start_s = 0);
// Every device takes its first chunk before any device takes a second, and in Hybrid the
// CPU worker its first run too (waiting at most 10 s for one that never asks), so that a
// test can count on each worker meshing something; chunks are otherwise pulled by
// whichever worker is free.
void opencl_deal_first_chunks(bool deal);
// Hybrid always splits the volume between the CPU worker and the devices, instead of choosing
// the CPU engine or a device alone where earlier calls found that quicker (for tests of the split).
void opencl_hybrid_split_only(bool split_only);
// Runs `f` (empty: nothing) in Hybrid's CPU worker just before it counts again a piece a device
// counted, to take it over: a test changes the volume there, as a caller's thread could.
void opencl_before_take_over(std::function<void()> f);
// Runs `f(recounted)` (empty: nothing) before a piece a device counted is generated: on the
// device (false), or on the CPU engine after it counted the piece again (true: a take-over, or
// a device out of memory), so that a test changes the volume between the passes there.
void opencl_before_generate(std::function<void(bool recounted)> f);
// Runs f holding the device registry's lock, as a thread inside devices() would; with
// `as_discovery`, as one caught discovering (the device list half built).
void opencl_with_registry_locked(bool as_discovery, const std::function<void()>& f);
// Builds an OpenCL C program on device `device` the way the engine builds its kernels:
// a failure throws Error with the device name and the build log.
void opencl_build_program(const std::string& source, const std::string& options, int device = 0);
#endif

}  // namespace voxmesh::detail
