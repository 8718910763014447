#include "nhdyn/model/event.hpp"

namespace nhdyn {

const char* event_direction_name(EventDirection direction) {
  switch (direction) {
    case EventDirection::rising: return "rising";
    case EventDirection::falling: return "falling";
    case EventDirection::both: return "both";
  }
  return "?";
}

const char* event_action_name(EventAction action) { return action == EventAction::stop ? "stop" : "record"; }

}  // namespace nhdyn
