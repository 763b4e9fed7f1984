// An OpenCL loader layer for the tests: it fails chosen calls with chosen errors. PoCL on the
// host never runs out of device memory, so without it the engine's recovery (smaller chunks,
// the CPU engine taking a chunk over, a clear Error for any other failure) would never run.
// ocl-icd loads it from OPENCL_LAYERS when the process first calls OpenCL; a test finds it with
// dlopen(RTLD_NOLOAD) and says what to fail with voxmesh_cl_fault_set.
#define CL_TARGET_OPENCL_VERSION 300
#include <CL/cl_layer.h>

#include <algorithm>
#include <cstring>
#include <mutex>
#include <string>

#define LAYER_EXPORT extern "C" __attribute__((visibility("default")))

namespace {

_cl_icd_dispatch g_dispatch{};
const _cl_icd_dispatch* g_next = nullptr;

std::mutex g_mutex;
std::string g_kernel;              // kernel whose launches fail, or a transfer call's name ("" = none)
cl_int g_kernel_error = CL_SUCCESS;
std::size_t g_buffer_over = 0;     // buffers larger than this fail (0 = none)
unsigned long long g_skip = 0;     // matching calls still to let through before the first fault
long long g_left = 0;              // faults still to give; negative = no end
unsigned long long g_given = 0;    // faults given since the last voxmesh_cl_fault_set

bool take_fault() {  // g_mutex held; called for each matching call
    if (g_left == 0) return false;
    if (g_skip > 0) {
        --g_skip;
        return false;
    }
    if (g_left > 0) --g_left;
    ++g_given;
    return true;
}

cl_mem CL_API_CALL create_buffer(cl_context context, cl_mem_flags flags, size_t size, void* host_ptr,
                                 cl_int* errcode_ret) {
    {
        std::lock_guard<std::mutex> lock(g_mutex);
        if (g_buffer_over > 0 && size > g_buffer_over && take_fault()) {
            if (errcode_ret) *errcode_ret = CL_MEM_OBJECT_ALLOCATION_FAILURE;
            return nullptr;
        }
    }
    return g_next->clCreateBuffer(context, flags, size, host_ptr, errcode_ret);
}

std::string kernel_name(cl_kernel kernel) {
    char name[128] = {};
    if (g_next->clGetKernelInfo(kernel, CL_KERNEL_FUNCTION_NAME, sizeof name - 1, name, nullptr) != CL_SUCCESS) return {};
    return name;
}

cl_int CL_API_CALL enqueue_kernel(cl_command_queue queue, cl_kernel kernel, cl_uint dims, const size_t* offset,
                                  const size_t* global, const size_t* local, cl_uint waits, const cl_event* wait_list,
                                  cl_event* event) {
    {
        std::lock_guard<std::mutex> lock(g_mutex);
        if (!g_kernel.empty() && kernel_name(kernel) == g_kernel && take_fault()) return g_kernel_error;
    }
    return g_next->clEnqueueNDRangeKernel(queue, kernel, dims, offset, global, local, waits, wait_list, event);
}

// A transfer by the name it has in the API: clEnqueueReadBuffer, clEnqueueWriteBuffer,
// clEnqueueCopyBuffer, clEnqueueMapBuffer.
bool transfer_fails(const char* api) {
    std::lock_guard<std::mutex> lock(g_mutex);
    return g_kernel == api && take_fault();
}

cl_int CL_API_CALL read_buffer(cl_command_queue queue, cl_mem buffer, cl_bool blocking, size_t offset, size_t size,
                               void* ptr, cl_uint waits, const cl_event* wait_list, cl_event* event) {
    if (transfer_fails("clEnqueueReadBuffer")) return g_kernel_error;
    return g_next->clEnqueueReadBuffer(queue, buffer, blocking, offset, size, ptr, waits, wait_list, event);
}

cl_int CL_API_CALL write_buffer(cl_command_queue queue, cl_mem buffer, cl_bool blocking, size_t offset, size_t size,
                                const void* ptr, cl_uint waits, const cl_event* wait_list, cl_event* event) {
    if (transfer_fails("clEnqueueWriteBuffer")) return g_kernel_error;
    return g_next->clEnqueueWriteBuffer(queue, buffer, blocking, offset, size, ptr, waits, wait_list, event);
}

cl_int CL_API_CALL copy_buffer(cl_command_queue queue, cl_mem from, cl_mem to, size_t from_offset, size_t to_offset,
                               size_t size, cl_uint waits, const cl_event* wait_list, cl_event* event) {
    if (transfer_fails("clEnqueueCopyBuffer")) return g_kernel_error;
    return g_next->clEnqueueCopyBuffer(queue, from, to, from_offset, to_offset, size, waits, wait_list, event);
}

void* CL_API_CALL map_buffer(cl_command_queue queue, cl_mem buffer, cl_bool blocking, cl_map_flags flags,
                             size_t offset, size_t size, cl_uint waits, const cl_event* wait_list, cl_event* event,
                             cl_int* errcode_ret) {
    if (transfer_fails("clEnqueueMapBuffer")) {
        if (errcode_ret) *errcode_ret = g_kernel_error;
        return nullptr;
    }
    return g_next->clEnqueueMapBuffer(queue, buffer, blocking, flags, offset, size, waits, wait_list, event, errcode_ret);
}

}  // namespace

// Launches of `kernel` (or calls of the transfer of that name) fail with `kernel_error`, buffers over `buffer_over` bytes with
// CL_MEM_OBJECT_ALLOCATION_FAILURE: `times` faults in all (negative: no end) after `skip`
// matching calls went through. Empty and 0 turn either off. Clears the count of faults given.
LAYER_EXPORT void voxmesh_cl_fault_set(const char* kernel, int kernel_error, unsigned long long buffer_over,
                                       unsigned long long skip, long long times) {
    std::lock_guard<std::mutex> lock(g_mutex);
    g_kernel = kernel ? kernel : "";
    g_kernel_error = kernel_error;
    g_buffer_over = buffer_over;
    g_skip = skip;
    g_left = times;
    g_given = 0;
}

LAYER_EXPORT unsigned long long voxmesh_cl_fault_given() {
    std::lock_guard<std::mutex> lock(g_mutex);
    return g_given;
}

LAYER_EXPORT cl_int CL_API_CALL clGetLayerInfo(cl_layer_info param_name, size_t param_value_size, void* param_value,
                                               size_t* param_value_size_ret) {
    if (param_name != CL_LAYER_API_VERSION) return CL_INVALID_VALUE;
    if (param_value) {
        if (param_value_size < sizeof(cl_layer_api_version)) return CL_INVALID_VALUE;
        *static_cast<cl_layer_api_version*>(param_value) = CL_LAYER_API_VERSION_100;
    }
    if (param_value_size_ret) *param_value_size_ret = sizeof(cl_layer_api_version);
    return CL_SUCCESS;
}

LAYER_EXPORT cl_int CL_API_CALL clInitLayer(cl_uint num_entries, const _cl_icd_dispatch* target_dispatch,
                                            cl_uint* num_entries_ret, const _cl_icd_dispatch** layer_dispatch_ret) {
    constexpr cl_uint ours = sizeof(_cl_icd_dispatch) / sizeof(void*);
    if (!target_dispatch || !num_entries_ret || !layer_dispatch_ret) return CL_INVALID_VALUE;
    // The loader's table may be shorter than this header's: the entries past it stay null.
    std::memcpy(&g_dispatch, target_dispatch, std::min(num_entries, ours) * sizeof(void*));
    g_next = target_dispatch;
    g_dispatch.clCreateBuffer = &create_buffer;
    g_dispatch.clEnqueueNDRangeKernel = &enqueue_kernel;
    g_dispatch.clEnqueueReadBuffer = &read_buffer;
    g_dispatch.clEnqueueWriteBuffer = &write_buffer;
    g_dispatch.clEnqueueCopyBuffer = &copy_buffer;
    g_dispatch.clEnqueueMapBuffer = &map_buffer;
    *layer_dispatch_ret = &g_dispatch;
    *num_entries_ret = ours;
    return CL_SUCCESS;
}
