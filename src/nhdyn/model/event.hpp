// An event of a model: a function g(t, q, q') (or of q'', R and the contact forces too) whose crossings of zero a run locates and reports
// (analysis/simulation.hpp), optionally ending the run there. Written in a model file as
// [[events]] (docs/model-format.md) or on the command line (--stop-when, --event); compiled from
// its expression by the symbolic layer (symbolic/events.hpp) into a tape (straight-line code) that
// reads the model's parameters, so that --set and set_parameter apply to events too.
#pragma once

#include <string>

#include "nhdyn/model/tape.hpp"

namespace nhdyn {

// Which crossings count: g going from negative to positive, from positive to negative, or both.
enum class EventDirection { rising, falling, both };
// What a crossing does: end the run there, or only record it and go on.
enum class EventAction { stop, record };

// "rising", "falling", "both"; "stop", "record".
const char* event_direction_name(EventDirection direction);
const char* event_action_name(EventAction action);

struct Event {
  std::string name;
  std::string expression;  // as the user wrote it: g, or a condition such as "abs(phi) > 1"
  std::string where;       // where it was written ("file:line:column", "--stop-when"), for messages
  EventDirection direction = EventDirection::both;
  EventAction action = EventAction::record;
  // Written as a condition (lhs > rhs) that becomes true at the crossing: a run whose initial state
  // already satisfies it is refused rather than stopped at once.
  bool condition = false;
  Tape g;  // one output, g(t, q, q'); reads the model's parameters (bind before running)
  // g reads q'' or the reactions R (through an output, model/output.hpp): g is then in the
  // dynamics layout (2n coordinates, [q; q''] and [q'; R]) and each evaluation solves the dynamics
  // at the state first (analysis/events.hpp).
  bool dynamics = false;
  // g reads a contact-force column (NAME_N, ...: model/contact_forces.hpp; implies `dynamics`): g
  // is then in the contact layout, 2n + 6 c coordinates (c the model's wheels and knife edges),
  // [q; q''; F] and [q'; R; 0] with F the values of ContactForceData::values, and each evaluation
  // computes the contact forces after the dynamics (analysis/events.hpp).
  bool contact_forces = false;
};

}  // namespace nhdyn
