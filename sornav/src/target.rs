//! Targets: an object category of the vocabulary, given directly or as a
//! free-text request ("find the television" -> `tv_monitor`).

use serde::{Deserialize, Serialize};
use sornav_supervisor::{OBJECTNAV_CATEGORIES, normalize_label};

use crate::error::AgentError;

/// Words of a request that never name an object.
const STOP_WORDS: [&str; 38] = [
    "a", "an", "the", "find", "go", "to", "get", "me", "please", "search", "for", "look", "locate",
    "navigate", "take", "bring", "show", "where", "is", "are", "my", "some", "any", "can", "you",
    "i", "want", "need", "of", "head", "move", "toward", "towards", "drive", "and", "or",
    "nearest", "closest",
];

/// Longest phrase (in words) looked up as a label.
const MAX_PHRASE_WORDS: usize = 3;

/// The categories an agent can search for.
///
/// Built from the ObjectNav categories and the object labels of the sensor
/// vocabulary, all normalised with the supervisor's
/// [`normalize_label`](sornav_supervisor::normalize_label).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Vocabulary {
    categories: Vec<String>,
}

/// A resolved target: the category and the request it came from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Target {
    /// Normalised category (`tv_monitor`, `toilet`, ...).
    pub category: String,
    /// The request as given.
    pub request: String,
}

impl Vocabulary {
    /// A vocabulary of the ObjectNav categories plus `labels` (normalised;
    /// structural labels dropped; duplicates removed).
    pub fn new<'a>(labels: impl IntoIterator<Item = &'a str>) -> Self {
        let mut categories: Vec<String> = OBJECTNAV_CATEGORIES
            .iter()
            .copied()
            .chain(labels)
            .filter_map(normalize_label)
            .collect();
        categories.sort();
        categories.dedup();
        Self { categories }
    }

    /// The categories, sorted.
    pub fn categories(&self) -> &[String] {
        &self.categories
    }

    /// Whether `category` (already normalised) is in the vocabulary.
    pub fn contains(&self, category: &str) -> bool {
        self.categories
            .binary_search_by(|c| c.as_str().cmp(category))
            .is_ok()
    }

    /// Resolves a category name or a free-text request.
    ///
    /// # Algorithm
    /// The request is lower-cased and split into words at white space and
    /// punctuation (`_` and `-` are kept inside words); stop words ("find",
    /// "the", "please", ...) split it into phrases. Within each phrase,
    /// windows of up to three words are tried longest first, left to right,
    /// each through `normalize_label` (synonyms: "television" -> `tv_monitor`,
    /// "couch" -> `sofa`) and, failing that, with a plural `s` / `es`
    /// removed. The first window that names a category of the vocabulary
    /// wins, so "the chair next to the bed" asks for a chair.
    ///
    /// # Errors
    /// [`AgentError::UnknownTarget`] when no window names a category.
    ///
    /// # Complexity
    /// O(w * 3 * (s + log c)) for w words, s synonyms and c categories.
    ///
    /// # Examples
    /// ```
    /// use sornav::Vocabulary;
    /// let v = Vocabulary::new(["tv", "cabinet"]);
    /// assert_eq!(v.resolve("find the television")?.category, "tv_monitor");
    /// assert_eq!(v.resolve("Go to the couch, please")?.category, "sofa");
    /// assert_eq!(v.resolve("toilets")?.category, "toilet");
    /// assert!(v.resolve("find the spaceship").is_err());
    /// # Ok::<(), sornav::AgentError>(())
    /// ```
    pub fn resolve(&self, request: &str) -> Result<Target, AgentError> {
        let lowered = request.to_lowercase();
        let words: Vec<&str> = lowered
            .split(|c: char| !(c.is_alphanumeric() || c == '_' || c == '-'))
            .filter(|w| !w.is_empty())
            .collect();
        let phrases: Vec<&[&str]> = words
            .split(|w| STOP_WORDS.contains(w))
            .filter(|p| !p.is_empty())
            .collect();
        for len in (1..=MAX_PHRASE_WORDS).rev() {
            for phrase in &phrases {
                for window in phrase.windows(len) {
                    if let Some(category) = self.match_phrase(&window.join(" ")) {
                        return Ok(Target {
                            category,
                            request: request.to_owned(),
                        });
                    }
                }
            }
        }
        // The whole request as one label (keeps "tv_monitor" and oddities).
        if let Some(category) = self.match_phrase(request) {
            return Ok(Target {
                category,
                request: request.to_owned(),
            });
        }
        Err(AgentError::UnknownTarget {
            request: request.to_owned(),
            known: self.categories.join(", "),
        })
    }

    fn match_phrase(&self, phrase: &str) -> Option<String> {
        let direct = normalize_label(phrase).filter(|c| self.contains(c));
        direct.or_else(|| {
            ["es", "s"].iter().find_map(|suffix| {
                phrase
                    .strip_suffix(suffix)
                    .filter(|stem| !stem.is_empty())
                    .and_then(normalize_label)
                    .filter(|c| self.contains(c))
            })
        })
    }
}
