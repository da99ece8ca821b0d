//! The OpenAI chat-completions wire format of the LLM policy: the compact
//! snapshot shown to the model, the answer type and its strict JSON schema,
//! request bodies and answer validation.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value, json};

use std::collections::HashMap;

use crate::context::{Candidate, RegionSnapshot};
use crate::label::normalize_label;
use crate::policy::PolicyDecision;

use super::LlmFailure;

/// The system prompt: the asymmetric context-gate rule and an answer
/// example of each action that conforms to [`answer_schema`].
pub const SYSTEM_PROMPT: &str = "You supervise a robot searching a building for a target object. \
Input: the target; the objects around the robot (\"here\"), counted per label; candidate regions it could move to \
(id; floor relative to the robot's: 0 same, 1 up, -1 down; path distance in m; objects near them, counted per label; \
no objects on another floor means unexplored stairs). \
Relocate ONLY when the objects here clearly contradict the kind of room where the target is found \
(for example a bedroom when looking for a toilet); if they are relevant, mixed, sparse or uncertain, continue exploring. \
When leaving, choose the candidate whose objects best fit the target, preferring nearer ones. \
Answer one JSON object, for example {\"action\":\"continue_explore\",\"cluster_id\":null,\"reason\":\"a kitchen can hold a chair\"} \
or {\"action\":\"relocate_cluster\",\"cluster_id\":2,\"reason\":\"a bedroom here; 2 has a sink\"}, \
with a cluster_id from the candidates and a reason of a few words.";

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

fn round1(x: f64) -> f64 {
    (x * 10.0).round() / 10.0
}

/// `{"label": count, ...}` of normalised labels, most frequent first (ties
/// by label), as JSON text.
fn label_counts<'a>(labels: impl Iterator<Item = &'a str>) -> String {
    let mut counts: HashMap<String, u32> = HashMap::new();
    for l in labels {
        let name = normalize_label(l).unwrap_or_else(|| l.trim().to_lowercase());
        *counts.entry(name).or_insert(0) += 1;
    }
    let mut sorted: Vec<(String, u32)> = counts.into_iter().collect();
    sorted.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
    let items: Vec<String> = sorted
        .iter()
        .map(|(label, n)| format!("{}:{n}", Value::String(label.clone())))
        .collect();
    format!("{{{}}}", items.join(","))
}

/// The labels of a candidate's objects within `radius_m` of it.
fn near_labels(candidate: &Candidate, radius_m: f64) -> impl Iterator<Item = &str> {
    candidate
        .context
        .iter()
        .filter(move |o| o.distance_m <= radius_m)
        .map(|o| o.label.as_str())
}

/// The compact JSON snapshot sent as the user message, keys in this order:
/// `target`, `here` (the robot's objects counted per normalised label) and
/// `candidates`, each `{id, floor, distance_m, objects}` with `id` its
/// 1-based position (the answer's `cluster_id`), `floor` relative to the
/// robot's, the distance rounded to decimetres and the objects within
/// `candidate_radius_m` of it counted per label. Equal situations give
/// byte-identical requests (and cache hits).
///
/// # Complexity
/// O(size of the snapshot).
pub fn snapshot_json(snapshot: &RegionSnapshot, candidate_radius_m: f64) -> String {
    let target =
        normalize_label(&snapshot.target).unwrap_or_else(|| snapshot.target.trim().to_lowercase());
    let here = label_counts(snapshot.local_context.iter().map(|o| o.label.as_str()));
    let candidates: Vec<String> = snapshot
        .candidates
        .iter()
        .enumerate()
        .map(|(i, c)| {
            format!(
                "{{\"id\":{},\"floor\":{},\"distance_m\":{},\"objects\":{}}}",
                i + 1,
                c.floor,
                json!(round1(c.distance_m)),
                label_counts(near_labels(c, candidate_radius_m))
            )
        })
        .collect();
    format!(
        "{{\"target\":{},\"here\":{here},\"candidates\":[{}]}}",
        Value::String(target),
        candidates.join(",")
    )
}

/// The candidate an answer's `cluster_id` (a 1-based position in the
/// snapshot, see [`snapshot_json`]) names.
pub fn named_candidate(snapshot: &RegionSnapshot, id: u64) -> Option<&Candidate> {
    let index = usize::try_from(id).ok()?.checked_sub(1)?;
    snapshot.candidates.get(index)
}

/// Whether the candidate an asynchronous answer chose (`id`, a position in
/// `asked`) still fits `current`: the same cluster id is offered, on the
/// same floor, and its surroundings (labels within `radius_m`) overlap the
/// ones the model saw by at least half (Jaccard; both empty counts as the
/// same). Cluster ids are only meaningful within one snapshot, so the
/// surroundings confirm it is the same region. Returns its position in
/// `current` (1-based).
///
/// # Complexity
/// O(size of both snapshots).
pub fn still_fits(
    id: u64,
    asked: &RegionSnapshot,
    current: &RegionSnapshot,
    radius_m: f64,
) -> Option<u64> {
    let then = named_candidate(asked, id)?;
    let (index, now) = current
        .candidates
        .iter()
        .enumerate()
        .find(|(_, c)| c.cluster_id == then.cluster_id)?;
    if now.floor != then.floor {
        return None;
    }
    let set = |c: &Candidate| -> std::collections::BTreeSet<String> {
        near_labels(c, radius_m)
            .map(|l| normalize_label(l).unwrap_or_else(|| l.trim().to_lowercase()))
            .collect()
    };
    let (a, b) = (set(then), set(now));
    let union = a.union(&b).count();
    let common = a.intersection(&b).count();
    (union == 0 || 2 * common >= union).then_some(index as u64 + 1)
}

/// Prompt and completion token counts of a chat-completions body
/// (`usage`), 0 when absent.
pub fn parse_usage(body: &str) -> (u64, u64) {
    let Ok(v) = serde_json::from_str::<Value>(body) else {
        return (0, 0);
    };
    let count = |k: &str| {
        v.pointer(&format!("/usage/{k}"))
            .and_then(Value::as_u64)
            .unwrap_or(0)
    };
    (count("prompt_tokens"), count("completion_tokens"))
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
    /// `response_format: {type: json_object, schema}` with the schema in the
    /// system prompt too, for servers without `json_schema`.
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
    let schema = answer_schema();
    let (response_format, system) = match format {
        ResponseFormat::JsonSchema => (
            json!({
                "type": "json_schema",
                "json_schema": {"name": "supervisor_decision", "strict": true, "schema": schema},
            }),
            SYSTEM_PROMPT.to_owned(),
        ),
        // Servers without json_schema: the schema in the prompt, and in
        // `schema` for servers that constrain json_object with it
        // (llama-cpp-python).
        ResponseFormat::JsonObject => (
            json!({"type": "json_object", "schema": schema}),
            format!("{SYSTEM_PROMPT} JSON schema of the answer: {schema}"),
        ),
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
            {"role": "system", "content": system},
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

/// Validates an answer against the snapshot it answers; the answer's
/// `cluster_id` is a candidate's position in [`snapshot_json`] (1-based),
/// the decision names the candidate's real cluster id.
///
/// # Errors
/// [`LlmFailure::InvalidAnswer`] for a relocation without a cluster id,
/// [`LlmFailure::UnknownCluster`] for an id not among the candidates.
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
            let cluster = named_candidate(snapshot, id)
                .ok_or(LlmFailure::UnknownCluster(id))?
                .cluster_id;
            Ok(PolicyDecision::relocate(
                cluster,
                format!(
                    "model: relocate to cluster {cluster} ({})",
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
