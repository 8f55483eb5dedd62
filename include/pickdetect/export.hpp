// SPDX-License-Identifier: LGPL-2.1-or-later
// PICKDETECT_API marks what libpickdetect exports: it is built with hidden visibility, so that
// the stages of the method stay internal.
#pragma once

#if defined(__GNUC__) || defined(__clang__)
#define PICKDETECT_API __attribute__((visibility("default")))
#else
#define PICKDETECT_API
#endif
