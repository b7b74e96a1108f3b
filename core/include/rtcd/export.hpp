// The public API's symbols: every target is compiled with hidden
// visibility, and what a public header declares between RTCD_PUBLIC_BEGIN
// and RTCD_PUBLIC_END is what a shared librtcd exports.
#pragma once

#define RTCD_PUBLIC_BEGIN _Pragma("GCC visibility push(default)")
#define RTCD_PUBLIC_END _Pragma("GCC visibility pop")
