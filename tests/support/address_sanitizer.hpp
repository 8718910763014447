// Whether this test executable is built with AddressSanitizer, which owns malloc: the allocation
// tests then count at operator new instead of interposing malloc. GCC says so with
// __SANITIZE_ADDRESS__, clang 14 only through __has_feature.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define NHDYN_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define NHDYN_ADDRESS_SANITIZER 1
#endif
#endif
