// The control for tests/cross/no_libm_elementary.sh: an object that needs libm's exp, which the check must reject.
#include <cmath>

double lever_uses_libm(double x) { return std::exp(x); }
