// One checked path for every OpenCL call: a failure throws RuntimeFailure naming the call, the error
// and the file:line of the call.
#pragma once
#ifndef CL_TARGET_OPENCL_VERSION
#define CL_TARGET_OPENCL_VERSION 120
#endif
#include <CL/cl.h>
#include <CL/cl_ext.h>

#include <string>

#include "runtime/errors.h"

const char* cl_error_name(cl_int code);
[[noreturn]] void cl_fail(const char* call, cl_int code, const char* file, int line);

#define CL_CHECK(call)                                                      \
  do {                                                                      \
    cl_int cl_check_code_ = (call);                                         \
    if (cl_check_code_ != CL_SUCCESS) cl_fail(#call, cl_check_code_, __FILE__, __LINE__); \
  } while (0)

// For calls that return an object and report through an error argument: CL_CHECKED(clCreateBuffer, ...).
#define CL_CHECKED(fn, ...)                                                    \
  [&] {                                                                        \
    cl_int cl_checked_code_ = CL_SUCCESS;                                      \
    auto cl_checked_result_ = fn(__VA_ARGS__, &cl_checked_code_);              \
    if (cl_checked_code_ != CL_SUCCESS) cl_fail(#fn, cl_checked_code_, __FILE__, __LINE__); \
    return cl_checked_result_;                                                 \
  }()
