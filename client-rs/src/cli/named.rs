//! Frames as the tools print them: the JSON of the wire with the codes also in words.

use serde_json::{Value, json};
use vas_client::words::{event_name, grasp_name, hand_name};
use vas_client::{Frame, HandSegment, SceneWords};

/// `frame` as a JSON object (`{"event":{...}}`, `{"hand":{...}}`...), its codes kept and their
/// names added: events get `kind_name`, `grasp_name`, `part_name`, `other_name`, `hand_name`,
/// `user_name` and `text`; hand frames `grasp_name`, `hand_name`, `user_name` and
/// `touching_names`; force frames `hand_name` and `user_name`; parts frames each part's `name`;
/// clearance frames each pair's `part_name`, `other_name` and `text`.
pub fn named(frame: &Frame, words: &SceneWords) -> serde_json::Result<Value> {
    let mut value = serde_json::to_value(frame)?;
    let Some((_, inner)) = value
        .as_object_mut()
        .and_then(|outer| outer.iter_mut().next())
    else {
        return Ok(value);
    };
    let Some(fields) = inner.as_object_mut() else {
        return Ok(value);
    };
    let names = match frame {
        Frame::Event(event) => json!({
            "kind_name": event_name(event.kind),
            "grasp_name": grasp_name(event.grasp_type),
            "part_name": words.part(event.part),
            "other_name": words.part(event.other),
            "hand_name": hand_name(event.hand),
            "user_name": words.user(event.user),
            "text": words.event(event),
        }),
        Frame::Hand(hand) => json!({
            "grasp_name": grasp_name(hand.grasp_type),
            "hand_name": hand_name(hand.hand),
            "user_name": words.user(hand.user),
            "touching_names": HandSegment::ALL
                .iter()
                .filter(|segment| hand.touching & segment.bit() != 0)
                .map(|segment| segment.name())
                .collect::<Vec<_>>(),
        }),
        Frame::Parts(parts) => {
            if let Some(Value::Array(states)) = fields.get_mut("parts") {
                for (state, part) in states.iter_mut().zip(&parts.parts) {
                    if let Some(state) = state.as_object_mut() {
                        state.insert("name".into(), words.part(part.id).into());
                    }
                }
            }
            return Ok(value);
        }
        Frame::Clearance(clearance) => {
            if let Some(Value::Array(pairs)) = fields.get_mut("pairs") {
                for (named, pair) in pairs.iter_mut().zip(clearance.listed()) {
                    if let Some(named) = named.as_object_mut() {
                        named.insert("part_name".into(), words.part(pair.part).into());
                        named.insert("other_name".into(), words.part(pair.other).into());
                        named.insert("text".into(), words.clearance(pair).into());
                    }
                }
            }
            return Ok(value);
        }
        Frame::Force(force) => json!({
            "hand_name": hand_name(force.hand),
            "user_name": words.user(force.user),
        }),
        Frame::Geometry(_) => return Ok(value),
    };
    if let Value::Object(names) = names {
        fields.extend(names);
    }
    Ok(value)
}
