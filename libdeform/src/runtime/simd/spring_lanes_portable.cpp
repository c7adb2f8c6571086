// SpringCrowdJob's lane kernel built for the compiler's baseline target (SSE2 on x86-64), for every CPU.
#define DEFORM_SPRING_ENTRY spring_lanes_portable
#include "spring_lanes_kernel.inl"
