//! The OpenAI chat-completions wire format of the LLM policy: the compact
//! snapshot shown to the model, the answer type and its strict JSON schema,
//! request bodies and answer validation.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value, json};

use crate::context::RegionSnapshot;
use crate::label::normalize_label;
use crate::policy::PolicyDecision;

use super::LlmFailure;

/// The system prompt: the asymmetric context-gate rule.
pub const SYSTEM_PROMPT: &str = "You supervise a robot searching a building for an object of a target category. \
You receive a JSON snapshot: the target, the objects around the robot (label, support = amount of evidence), \
and candidate regions the robot could relocate to (cluster_id, graph distance in metres, objects near them). \
Decide whether the robot should abandon its current region. Relocate ONLY when the objects around the robot \
clearly contradict the kind of room where the target is usually found (for example a bedroom when looking for a toilet). \
If the surroundings are relevant, mixed, sparse or uncertain, continue exploring. Only once leaving is justified, \
choose the candidate whose objects are most compatible with the target, preferring nearer ones; a distant region \
that merely looks more promising is never a reason to leave. \
Answer with a single JSON object: {\"action\":\"continue_explore\"} or \
{\"action\":\"relocate_cluster\",\"cluster_id\":N,\"reason\":\"...\"}, using only a cluster_id from the candidates.";

/// The action field of an answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LlmAction {
    /// Keep exploring the current region.
    ContinueExplore,
    /// Relocate to `cluster_id`.
    RelocateCluster,
}

/// The model's answer. Unknown fields are rejected.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LlmAnswer {
    /// `continue_explore` or `relocate_cluster`.
    pub action: LlmAction,
    /// The chosen cluster for `relocate_cluster` (null otherwise).
    #[serde(default)]
    pub cluster_id: Option<u64>,
    /// A short justification.
    #[serde(default)]
    pub reason: Option<String>,
}

fn round2(x: f64) -> f64 {
    (x * 100.0).round() / 100.0
}

/// The compact JSON snapshot sent as the user message: labels normalised,
/// numbers rounded to centimetres / hundredths so that equal situations give
/// byte-identical requests (and cache hits).
///
/// # Complexity
/// O(size of the snapshot).
pub fn snapshot_json(snapshot: &RegionSnapshot) -> String {
    let label = |l: &str| normalize_label(l).unwrap_or_else(|| l.trim().to_lowercase());
    let local: Vec<Value> = snapshot
        .local_context
        .iter()
        .map(|o| json!({"label": label(&o.label), "support": round2(o.support)}))
        .collect();
    let candidates: Vec<Value> = snapshot
        .candidates
        .iter()
        .map(|c| {
            let ctx: Vec<Value> = c
                .context
                .iter()
                .map(|o| json!({"label": label(&o.label), "support": round2(o.support), "distance_m": round2(o.distance_m)}))
                .collect();
            json!({"cluster_id": c.cluster_id, "distance_m": round2(c.distance_m), "context": ctx})
        })
        .collect();
    json!({
        "target": label(&snapshot.target),
        "local_context": local,
        "candidates": candidates,
    })
    .to_string()
}

/// Keywords OpenAI's strict structured-output mode accepts; everything else
/// (`format`, `minimum`, `$schema`, `title`, `default`, ...) is removed.
const STRICT_KEYWORDS: [&str; 11] = [
    "type",
    "properties",
    "required",
    "additionalProperties",
    "enum",
    "anyOf",
    "items",
    "$defs",
    "$ref",
    "description",
    "const",
];

fn strictify(value: &mut Value) {
    match value {
        Value::Object(map) => {
            // strict mode has no `oneOf`; schemars emits it for documented
            // unit enums whose alternatives are disjoint constants anyway.
            if let Some(one_of) = map.remove("oneOf") {
                map.insert("anyOf".into(), one_of);
            }
            map.retain(|k, _| STRICT_KEYWORDS.contains(&k.as_str()));
            if let Some(Value::Object(props)) = map.get_mut("properties") {
                for v in props.values_mut() {
                    strictify(v);
                }
                let names: Vec<Value> = props.keys().cloned().map(Value::String).collect();
                map.insert("required".into(), Value::Array(names));
                map.insert("additionalProperties".into(), Value::Bool(false));
            }
            if let Some(Value::Object(defs)) = map.get_mut("$defs") {
                for v in defs.values_mut() {
                    strictify(v);
                }
            }
            for key in ["anyOf", "items"] {
                match map.get_mut(key) {
                    Some(Value::Array(items)) => items.iter_mut().for_each(strictify),
                    Some(v @ Value::Object(_)) => strictify(v),
                    _ => {}
                }
            }
        }
        Value::Array(items) => items.iter_mut().for_each(strictify),
        _ => {}
    }
}

/// The answer's JSON schema, generated from [`LlmAnswer`] with schemars and
/// made strict-mode compatible: every object lists all its properties as
/// required (optional ones are nullable), forbids additional properties and
/// uses only keywords strict mode supports.
///
/// # Complexity
/// O(size of the schema).
pub fn answer_schema() -> Value {
    let mut schema = schemars::schema_for!(LlmAnswer).to_value();
    strictify(&mut schema);
    let defs = match schema.as_object_mut().and_then(|m| m.remove("$defs")) {
        Some(Value::Object(defs)) => defs,
        _ => Map::new(),
    };
    inline_refs(&mut schema, &defs);
    schema
}

/// Replaces local `$ref`s by their (non-recursive) definitions and turns an
/// `anyOf` of string constants into an `enum`: the most widely supported
/// form across OpenAI strict mode and local grammar-constrained servers.
fn inline_refs(value: &mut Value, defs: &Map<String, Value>) {
    match value {
        Value::Object(map) => {
            if let Some(Value::String(r)) = map.get("$ref")
                && let Some(def) = r.strip_prefix("#/$defs/").and_then(|n| defs.get(n))
                && let Value::Object(def) = def.clone()
            {
                map.remove("$ref");
                for (k, v) in def {
                    map.entry(k).or_insert(v);
                }
            }
            for v in map.values_mut() {
                inline_refs(v, defs);
            }
            let consts: Option<Vec<Value>> = match map.get("anyOf") {
                Some(Value::Array(items)) => items
                    .iter()
                    .map(|i| match (i.get("const"), i.get("type")) {
                        (Some(c @ Value::String(_)), Some(Value::String(t))) if t == "string" => {
                            Some(c.clone())
                        }
                        _ => None,
                    })
                    .collect(),
                _ => None,
            };
            if let Some(consts) = consts {
                map.remove("anyOf");
                map.insert("type".into(), json!("string"));
                map.insert("enum".into(), Value::Array(consts));
            }
        }
        Value::Array(items) => items.iter_mut().for_each(|v| inline_refs(v, defs)),
        _ => {}
    }
}

/// How the request asks for JSON.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ResponseFormat {
    /// `response_format: {type: json_schema, json_schema: {strict: true, ...}}`.
    JsonSchema,
    /// `response_format: {type: json_object}`, for servers without schemas.
    JsonObject,
}

/// The request body for one snapshot (deterministic bytes).
///
/// # Complexity
/// O(size of the snapshot).
pub fn request_body(
    model: &str,
    temperature: f64,
    max_tokens: Option<u32>,
    snapshot_json: &str,
    format: ResponseFormat,
) -> String {
    let response_format = match format {
        ResponseFormat::JsonSchema => json!({
            "type": "json_schema",
            "json_schema": {"name": "supervisor_decision", "strict": true, "schema": answer_schema()},
        }),
        ResponseFormat::JsonObject => json!({"type": "json_object"}),
    };
    let mut body = Map::new();
    body.insert("model".into(), json!(model));
    body.insert("temperature".into(), json!(temperature));
    if let Some(m) = max_tokens {
        body.insert("max_tokens".into(), json!(m));
    }
    body.insert(
        "messages".into(),
        json!([
            {"role": "system", "content": SYSTEM_PROMPT},
            {"role": "user", "content": snapshot_json},
        ]),
    );
    body.insert("response_format".into(), response_format);
    Value::Object(body).to_string()
}

/// Extracts the answer from a chat-completions response body.
///
/// # Errors
/// [`LlmFailure::MalformedResponse`] when the body is not a chat completion
/// with a string `choices[0].message.content`;
/// [`LlmFailure::InvalidAnswer`] when the content is not exactly an
/// [`LlmAnswer`] (invalid JSON, unknown action, extra fields). A `reason`
/// longer than [`MAX_REASON_CHARS`] is cut to that length.
pub fn parse_answer(body: &str) -> Result<LlmAnswer, LlmFailure> {
    let v: Value = serde_json::from_str(body)
        .map_err(|e| LlmFailure::MalformedResponse(format!("body is not JSON: {e}")))?;
    let content = v
        .pointer("/choices/0/message/content")
        .and_then(Value::as_str)
        .ok_or_else(|| {
            LlmFailure::MalformedResponse("no string choices[0].message.content".into())
        })?;
    let mut answer: LlmAnswer = serde_json::from_str(content.trim()).map_err(|e| {
        LlmFailure::InvalidAnswer(format!("{e}: {:?}", clip(content, MAX_REASON_CHARS)))
    })?;
    if let Some(reason) = answer.reason.as_mut() {
        *reason = clip(reason, MAX_REASON_CHARS);
    }
    Ok(answer)
}

/// Longest `reason` kept from an answer, in characters: longer ones are
/// cut (and marked), so that a runaway model cannot grow decision logs,
/// episode records and the answer cache without bound (5 MB reasons grew
/// `episodes.jsonl` to 320 MB for 9 episodes). Invalid answers are quoted
/// in their error at most this long too.
pub const MAX_REASON_CHARS: usize = 500;

/// `text` cut to at most `max` characters, with a marker saying how long it
/// was when cut.
fn clip(text: &str, max: usize) -> String {
    match text.char_indices().nth(max) {
        None => text.to_owned(),
        Some((end, _)) => format!(
            "{}... [cut: {} characters]",
            &text[..end],
            text.chars().count()
        ),
    }
}

/// Validates an answer against the snapshot it answers.
///
/// # Errors
/// [`LlmFailure::InvalidAnswer`] for a relocation without a cluster id,
/// [`LlmFailure::UnknownCluster`] for a cluster id not among the candidates.
pub fn validate_answer(
    answer: &LlmAnswer,
    snapshot: &RegionSnapshot,
) -> Result<PolicyDecision, LlmFailure> {
    let reason = answer.reason.clone().filter(|r| !r.trim().is_empty());
    match answer.action {
        LlmAction::ContinueExplore => Ok(PolicyDecision::explore(format!(
            "model: continue exploring ({})",
            reason.as_deref().unwrap_or("no reason given")
        ))),
        LlmAction::RelocateCluster => {
            let id = answer.cluster_id.ok_or_else(|| {
                LlmFailure::InvalidAnswer("relocate_cluster without cluster_id".into())
            })?;
            if snapshot.candidate(id).is_none() {
                return Err(LlmFailure::UnknownCluster(id));
            }
            Ok(PolicyDecision::relocate(
                id,
                format!(
                    "model: relocate to cluster {id} ({})",
                    reason.as_deref().unwrap_or("no reason given")
                ),
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schema_is_strict() {
        let s = answer_schema();
        assert_eq!(s["additionalProperties"], json!(false));
        let req: Vec<&str> = s["required"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        assert_eq!(req, ["action", "cluster_id", "reason"]);
        let text = s.to_string();
        assert!(
            !text.contains("format") && !text.contains("minimum") && !text.contains("$schema"),
            "{text}"
        );
        assert!(
            !text.contains("$ref") && !text.contains("$defs") && !text.contains("anyOf"),
            "{text}"
        );
        assert_eq!(
            s["properties"]["action"]["enum"],
            json!(["continue_explore", "relocate_cluster"])
        );
        assert_eq!(s["properties"]["action"]["type"], "string");
    }

    /// Issue 21: a 5 MB reason was kept whole (and logged per decision).
    #[test]
    fn long_reasons_are_cut() {
        let wrap = |c: &str| {
            json!({"choices": [{"message": {"role": "assistant", "content": c}}]}).to_string()
        };
        let long = "é".repeat(5 << 20);
        let answer = parse_answer(&wrap(
            &json!({"action": "continue_explore", "reason": long}).to_string(),
        ))
        .unwrap();
        let reason = answer.reason.unwrap();
        assert!(reason.starts_with(&"é".repeat(MAX_REASON_CHARS)));
        assert!(
            reason.ends_with(&format!("[cut: {} characters]", 5 << 20)),
            "{}",
            &reason[reason.len() - 40..]
        );
        assert!(reason.chars().count() < MAX_REASON_CHARS + 40);
        // at the limit: kept as it is
        let exact = "r".repeat(MAX_REASON_CHARS);
        let answer = parse_answer(&wrap(
            &json!({"action": "continue_explore", "reason": exact}).to_string(),
        ))
        .unwrap();
        assert_eq!(answer.reason.as_deref(), Some(exact.as_str()));
        // an invalid answer quotes at most the limit of its content
        match parse_answer(&wrap(&format!(
            "{{\"action\":\"fly\",\"reason\":\"{}\"}}",
            "x".repeat(1 << 20)
        ))) {
            Err(LlmFailure::InvalidAnswer(m)) => {
                assert!(m.len() < 2 * MAX_REASON_CHARS, "{}", m.len())
            }
            other => panic!("expected an invalid answer, got {other:?}"),
        }
    }

    #[test]
    fn answers_parse_strictly() {
        let wrap = |c: &str| {
            json!({"choices": [{"message": {"role": "assistant", "content": c}}]}).to_string()
        };
        assert_eq!(
            parse_answer(&wrap(r#"{"action":"continue_explore"}"#))
                .unwrap()
                .action,
            LlmAction::ContinueExplore
        );
        assert!(matches!(
            parse_answer(&wrap(r#"{"action":"dance"}"#)),
            Err(LlmFailure::InvalidAnswer(_))
        ));
        assert!(matches!(
            parse_answer(&wrap(r#"{"action":"continue_explore","mood":"happy"}"#)),
            Err(LlmFailure::InvalidAnswer(_))
        ));
        assert!(matches!(
            parse_answer("<html>"),
            Err(LlmFailure::MalformedResponse(_))
        ));
        assert!(matches!(
            parse_answer(r#"{"choices":[]}"#),
            Err(LlmFailure::MalformedResponse(_))
        ));
    }
}
