// Compute-shader helpers.

// The index of this thread in a 1D dispatch whose groups spread over x and y
// (ShaderProgram::dispatch_threads: one dimension holds at most 65535 groups).
uint thread_index() {
    return gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
}
