// hawor/io/detail/stb.hpp — the one place that pulls in stb_image / stb_image_write.
//
// stb is a "single-header" C library: its implementation must be compiled in exactly one
// translation unit, which a header-only library cannot promise. Three configurations:
//   default              stb's implementation is compiled here with STB_IMAGE_STATIC and
//                        STB_IMAGE_WRITE_STATIC: every TU gets private (static) copies, so any
//                        number of TUs including hawor headers link without duplicate symbols.
//                        Decoders kept: PNG (needs zlib, which .npz inflating uses), JPEG, BMP.
//   HAWOR_STB_EXTERNAL   only the declarations are included; the program compiles stb itself
//                        (non-static, default allocator) in one of its own TUs.
//   HAWOR_NO_STB         no stb at all: .npz is limited to stored (uncompressed) members and
//                        deflated ones fail with a clear hawor::Error.
// Including <stb_image.h> yourself *before* hawor in the same TU is only valid with
// HAWOR_STB_EXTERNAL (otherwise the static implementation would clash with your declarations).
#pragma once

#if defined(HAWOR_NO_STB)

#define HAWOR_HAVE_STB 0
// ABI tag: the deflate-dependent classes live in a differently named inline namespace per
// configuration, so TUs built with and without stb can share one program without ODR clashes.
#define HAWOR_IO_DEFLATE_NS io_nostb

#else

#define HAWOR_HAVE_STB 1
#define HAWOR_IO_DEFLATE_NS io_stb

#if defined(HAWOR_STB_EXTERNAL)
#include <stb_image.h>
#include <stb_image_write.h>
// stb_image_write declares its zlib compressor only inside the implementation section.
extern "C" unsigned char* stbi_zlib_compress(unsigned char* data, int data_len, int* out_len,
                                             int quality);
#else
#if defined(STBI_INCLUDE_STB_IMAGE_H) || defined(INCLUDE_STB_IMAGE_WRITE_H)
#error "stb_image(_write).h was included before hawor/io: define HAWOR_STB_EXTERNAL (and compile stb yourself) or include hawor first"
#endif
#if defined(__GNUC__) || defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wunused-variable"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#endif
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#define STBI_ONLY_BMP
#define STBI_NO_STDIO
#include <stb_image.h>
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBI_WRITE_NO_STDIO
#include <stb_image_write.h>
#undef STB_IMAGE_IMPLEMENTATION
#undef STB_IMAGE_WRITE_IMPLEMENTATION
#if defined(__GNUC__) || defined(__clang__)
#pragma GCC diagnostic pop
#endif
#endif  // HAWOR_STB_EXTERNAL

#endif  // HAWOR_NO_STB

// Releases buffers returned by stbi_zlib_compress (stb_image_write's STBIW_FREE, free() unless
// the program's own stb build replaced the allocator: then define HAWOR_STBIW_FREE to match).
#ifndef HAWOR_STBIW_FREE
#include <cstdlib>
#define HAWOR_STBIW_FREE(p) std::free(p)
#endif
