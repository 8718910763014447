#include "nhdyn/frontend/events.hpp"

#include "nhdyn/symbolic/description.hpp"
#include "nhdyn/symbolic/events.hpp"

namespace nhdyn {

Event make_stop_condition(const LoadedModel& loaded, const std::string& condition) {
  if (loaded.description) return symbolic::make_stop_condition(loaded.description->spec(), loaded.model, condition);
  return symbolic::make_stop_condition(loaded.model, condition);
}

Event make_stop_condition(const Model& model, const std::string& condition) {
  return symbolic::make_stop_condition(model, condition);
}

Event make_record_event(const LoadedModel& loaded, const std::string& definition) {
  if (loaded.description) return symbolic::make_record_event(loaded.description->spec(), loaded.model, definition);
  return symbolic::make_record_event(loaded.model, definition);
}

Event make_record_event(const Model& model, const std::string& definition) {
  return symbolic::make_record_event(model, definition);
}

}  // namespace nhdyn
