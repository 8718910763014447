// The grounds' own files (grounds/*.cpp), one per ground type: each defines its type (a
// ContactGround, rolling_contact.hpp) and the function that returns its one instance, which the
// table of rolling_contact.cpp lists once. A new ground is a file in grounds/, its function here
// and a line in that table.
// Internal: the grounds are reached through contact_grounds() and find_contact_ground().
#pragma once

#include "nhdyn/symbolic/rolling_contact.hpp"

namespace nhdyn::symbolic::grounds {

const ContactGround& plane();
const ContactGround& surface();
const ContactGround& terrain();

}  // namespace nhdyn::symbolic::grounds
