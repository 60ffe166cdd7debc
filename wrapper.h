/* inimtrace: the one C header that bindgen reads (see build.rs). It pulls in Intel Embree's public
 * API, `rtcore.h`, from whichever major version build.rs found: Embree 4 when build.rs passes
 * -DINIMTRACE_EMBREE4, else Embree 3. Only `rtc*` functions and `RTC*` types/constants are kept. */
#if defined(INIMTRACE_EMBREE4)
#include <embree4/rtcore.h>
#else
#include <embree3/rtcore.h>
#endif
