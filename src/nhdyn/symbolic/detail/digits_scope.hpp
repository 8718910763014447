// GiNaC's precision for one computation: GiNaC::Digits is global, so it is set for the scope and
// put back on leaving it, even on a throw (the 50-digit reference, the start's contact point).
// Internal: a helper of the symbolic module, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <ginac/ginac.h>

namespace nhdyn::symbolic {

class DigitsScope {
 public:
  explicit DigitsScope(long digits) : saved_(GiNaC::Digits) { GiNaC::Digits = digits; }
  ~DigitsScope() { GiNaC::Digits = saved_; }
  DigitsScope(const DigitsScope&) = delete;
  DigitsScope& operator=(const DigitsScope&) = delete;

 private:
  long saved_;
};

}  // namespace nhdyn::symbolic
