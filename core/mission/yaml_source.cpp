// Stage 0 of the mission loader: YAML text to plain data with positions.
//
// yaml-cpp does the parsing; this file makes its output agree with PyYAML, which produced
// the fixtures' expectations: positions are recomputed from byte offsets with PyYAML's
// rules (columns count characters, a byte-order mark counts nothing), empty scalars are
// placed where PyYAML places them (just after the ':' or '-' that introduced them), and
// what yaml-cpp tolerates but PyYAML refuses is refused here too: tabs outside quoted
// scalars, block scalars and comments; duplicate anchors; several documents; block-mapping
// entries without a key or a ':'; empty flow entries; unclosed quoted scalars; values not
// indented past their key. Where the two would type a node apart (tags, anchor names with
// ':', line breaks other than LF, CRLF and CR) both readers refuse it.
#include "core/mission/yaml_source.hpp"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/exceptions.h>
#include <yaml-cpp/mark.h>
#include <yaml-cpp/parser.h>

#include <algorithm>
#include <cassert>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <sstream>
#include <unordered_set>

namespace keel::mission::detail {
namespace {

// ------------------------------------------------------------------------------------
// The text and its positions

// The text handed to yaml-cpp plus what is needed to turn yaml-cpp's byte offsets into
// PyYAML's line and column.
class Source {
public:
    explicit Source(const std::string& text) : buffer_(text) {
        // PyYAML treats a lone CR as a line break; yaml-cpp does not. Replacing it with LF
        // keeps every byte offset and makes both parsers see the same lines.
        for (std::size_t i = 0; i < buffer_.size(); ++i) {
            if (buffer_[i] == '\r' && (i + 1 == buffer_.size() || buffer_[i + 1] != '\n')) {
                buffer_[i] = '\n';
            }
        }
        if (buffer_.size() >= 3 && buffer_.compare(0, 3, "\xEF\xBB\xBF") == 0) {
            bom_bytes_ = 3;  // yaml-cpp strips a leading byte-order mark before counting
        }
        line_starts_.push_back(0);
        for (std::size_t i = 0; i < buffer_.size(); ++i) {
            if (buffer_[i] == '\n') line_starts_.push_back(i + 1);
        }
    }

    const std::string& buffer() const { return buffer_; }
    std::size_t size() const { return buffer_.size(); }
    char at(std::size_t offset) const { return offset < buffer_.size() ? buffer_[offset] : '\0'; }

    // Offset in the buffer of a yaml-cpp mark.
    std::size_t offset(const YAML::Mark& mark) const {
        if (mark.is_null() || mark.pos < 0) return 0;
        return std::min(buffer_.size(), static_cast<std::size_t>(mark.pos) + bom_bytes_);
    }

    std::size_t line_start(std::size_t offset) const {
        auto it = std::upper_bound(line_starts_.begin(), line_starts_.end(), offset);
        return *(it - 1);
    }

    // PyYAML's position of a byte offset: 1-based line; 1-based column counting
    // characters, where a byte-order mark does not count.
    Position position(std::size_t offset) const {
        offset = std::min(offset, buffer_.size());
        auto it = std::upper_bound(line_starts_.begin(), line_starts_.end(), offset);
        const auto line = static_cast<int>(it - line_starts_.begin());
        const std::size_t start = *(it - 1);
        // Marks mostly come in file order: go on from the last one when it is on the same
        // line, so that a document on one long line does not cost quadratic time.
        std::size_t from = start;
        int col = 1;
        if (cache_line_start_ == start && cache_offset_ <= offset) {
            from = cache_offset_;
            col = cache_col_;
        }
        for (std::size_t i = from; i < offset; ++i) {
            const auto byte = static_cast<unsigned char>(buffer_[i]);
            if ((byte & 0xC0) == 0x80) continue;  // continuation byte
            if (byte == 0xEF && buffer_.compare(i, 3, "\xEF\xBB\xBF") == 0) continue;
            ++col;
        }
        cache_line_start_ = start;
        cache_offset_ = offset;
        cache_col_ = col;
        return {line, col};
    }

    Position position(const YAML::Mark& mark) const {
        if (mark.is_null() || mark.pos < 0) return {1, 1};
        return position(offset(mark));
    }

    // Skips node properties (an anchor `&name` and a tag `!tag`) and the blanks, line
    // breaks and comments after them: the offset where the node's content starts.
    std::size_t skip_properties(std::size_t offset) const {
        for (int guard = 0; guard < 4; ++guard) {
            const char c = at(offset);
            if (c != '&' && c != '!') break;
            while (offset < size() && !is_blank_or_break(at(offset))) ++offset;
            offset = skip_blanks(offset);
        }
        return offset;
    }

    // Skips spaces, tabs, line breaks and comments.
    std::size_t skip_blanks(std::size_t offset) const {
        while (offset < size()) {
            const char c = at(offset);
            if (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
                ++offset;
            } else if (c == '#') {
                while (offset < size() && at(offset) != '\n') ++offset;
            } else {
                break;
            }
        }
        return offset;
    }

    // The plain null word ("~", "null", "Null", "NULL") written at `offset`, or "".
    std::string null_word_at(std::size_t offset) const {
        if (offset >= size()) return "";
        for (const char* word : {"null", "Null", "NULL", "~"}) {
            const std::string_view w(word);
            if (buffer_.compare(offset, w.size(), w) == 0 && ends_plain(offset + w.size())) {
                return std::string(w);
            }
        }
        return "";
    }

    // True when the text at `offset` (after spaces) is a ':' that makes what precedes it
    // a mapping key.
    bool colon_follows(std::size_t offset) const {
        while (at(offset) == ' ') ++offset;
        return at(offset) == ':' && is_blank_or_break_or_end(offset + 1);
    }

    // Where PyYAML puts an empty scalar whose yaml-cpp mark is `offset`: just after the
    // `indicator` (':' for a mapping value, '-' for a sequence entry) that introduced it,
    // when only blanks and comments separate them; otherwise at `offset`.
    std::size_t after_indicator(std::size_t offset, char indicator) const {
        std::size_t end = offset;
        for (bool first = true;; first = false) {
            const std::size_t begin = line_start_of_segment(end);
            // A token cannot start inside a comment, so only the end of the text can follow
            // one on its line: elsewhere skip the scan of the first line.
            std::size_t stop = first && offset < size() ? end : comment_start(begin, end);
            while (stop > begin && (at(stop - 1) == ' ' || at(stop - 1) == '\t' ||
                                    at(stop - 1) == '\n' || at(stop - 1) == '\r')) {
                --stop;
            }
            if (stop > begin) return at(stop - 1) == indicator ? stop : offset;
            if (begin == 0) return offset;
            end = begin - 1;  // the line break that ends the previous line
        }
    }

    // True when `offset` starts a line (after the byte-order mark on the first line) or
    // follows a blank: where a '#' starts a comment.
    bool starts_token(std::size_t offset) const {
        if (offset == 0 || offset == bom_bytes_) return true;
        const char before = at(offset - 1);
        return before == ' ' || before == '\t' || before == '\n';
    }

private:
    static bool is_blank_or_break(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
    bool is_blank_or_break_or_end(std::size_t offset) const {
        return offset >= size() || is_blank_or_break(at(offset));
    }
    // True when a plain scalar that has reached `offset` ends there: what follows is only
    // blanks up to the end of the line, a comment, a ':' that makes it a key, or a flow
    // indicator. ("null  x" and "null#x" are plain scalars that go on.)
    bool ends_plain(std::size_t offset) const {
        bool blank = false;
        while (at(offset) == ' ' || at(offset) == '\t') {
            ++offset;
            blank = true;
        }
        if (offset >= size()) return true;
        const char c = at(offset);
        if (c == '\n' || c == '\r' || c == ',' || c == ']' || c == '}') return true;
        if (c == '#') return blank;
        if (c == ':') return is_blank_or_break_or_end(offset + 1) || at(offset + 1) == ',' ||
                             at(offset + 1) == ']' || at(offset + 1) == '}';
        return false;
    }
    std::size_t line_start_of_segment(std::size_t end) const {
        // The start of the line holding the character just before `end` (or `end` itself
        // when it starts a line).
        if (end == 0) return 0;
        if (at(end - 1) == '\n') return end;
        return line_start(end - 1);
    }
    // Where a comment starts in [begin, end) of one line, or `end`; quotes are skipped.
    std::size_t comment_start(std::size_t begin, std::size_t end) const {
        char quote = 0;
        for (std::size_t i = begin; i < end; ++i) {
            const char c = at(i);
            if (quote != 0) {
                if (quote == '"' && c == '\\') {
                    ++i;
                } else if (c == quote) {
                    quote = 0;
                }
            } else if (c == '"' || c == '\'') {
                if (i == begin || is_blank_or_break(at(i - 1)) || at(i - 1) == ':' ||
                    at(i - 1) == '[' || at(i - 1) == '{' || at(i - 1) == ',') {
                    quote = c;
                }
            } else if (c == '#' && starts_token(i)) {
                return i;
            }
        }
        return end;
    }

    std::string buffer_;
    std::size_t bom_bytes_ = 0;
    std::vector<std::size_t> line_starts_;
    // The last position computed (see position()).
    mutable std::size_t cache_line_start_ = static_cast<std::size_t>(-1);
    mutable std::size_t cache_offset_ = 0;
    mutable int cache_col_ = 1;
};

// yaml-cpp decodes the escapes "\N" (U+0085) and "\_" (U+00A0) of a double-quoted
// scalar to one byte each, which is not UTF-8; every other byte of a value is. Encode
// those two as the characters they stand for.
std::string repair_escapes(const std::string& value) {
    if (!first_invalid_utf8(value)) return value;
    std::string out;
    out.reserve(value.size() + 8);
    std::size_t i = 0;
    while (i < value.size()) {
        const auto rest = std::string_view(value).substr(i);
        const auto bad = first_invalid_utf8(rest);
        const std::size_t good = bad.value_or(rest.size());
        out.append(rest.substr(0, good));
        i += good;
        if (!bad) break;
        const auto byte = static_cast<unsigned char>(value[i]);
        out += static_cast<char>(0xC0 | (byte >> 6));  // U+0080..U+00FF in two bytes
        out += static_cast<char>(0x80 | (byte & 0x3F));
        ++i;
    }
    return out;
}

// ------------------------------------------------------------------------------------
// The node graph yaml-cpp's events describe (aliases share nodes, as in PyYAML)

struct Node {
    enum class Kind : std::uint8_t { scalar, sequence, mapping };
    Kind kind = Kind::scalar;
    bool plain = true;  // a plain scalar (typed by the core schema), not quoted or block
    std::string text;
    Position position;
    std::vector<std::uint32_t> children;  // sequence items; mapping key, value, key, ...
};

struct SyntaxError {
    Position position;
    std::string message;
};

class GraphBuilder final : public YAML::EventHandler {
public:
    explicit GraphBuilder(const Source& source) : source_(source) {}

    std::vector<Node> nodes;
    std::optional<std::uint32_t> root;
    // Offsets where quoted and block scalars start (for the tab rule).
    std::vector<std::size_t> non_plain_starts;

    void OnDocumentStart(const YAML::Mark&) override {}
    void OnDocumentEnd() override {}

    void OnAnchor(const YAML::Mark& mark, const std::string& name) override {
        // YAML 1.2 lets an anchor name hold ':' (so `&a: x` is an anchor "a:"), PyYAML
        // ends the name there; refuse names either parser would read differently.
        const bool plain_name = std::all_of(name.begin(), name.end(), [](char c) {
            return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '_';
        });
        if (!plain_name) {
            throw SyntaxError{source_.position(mark),
                              "an anchor name is letters, digits, '-' and '_' (found '" + name +
                                  "')"};
        }
        if (!anchor_names_.insert(name).second) {
            throw SyntaxError{source_.position(mark), "found duplicate anchor '" + name + "'"};
        }
    }

    void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override {
        check_depth(mark);
        const std::size_t offset = source_.offset(mark);
        const std::size_t content = source_.skip_properties(offset);
        check_no_tag(mark, offset);
        check_entry(offset);
        if (content != offset && source_.at(content) == '*') {
            throw SyntaxError{source_.position(content), "expected the node content, but found an alias"};
        }
        note_key(offset);
        Node node;
        node.kind = Node::Kind::scalar;
        const bool key = in_key_slot();
        const std::string word = source_.null_word_at(content);
        if (key && word.empty() && content == offset) {
            // `? ` with nothing after it: yaml-cpp and PyYAML build different mappings
            // from it, and a mission has no use for an empty key; both readers refuse it.
            throw SyntaxError{source_.position(offset), "a mapping key is empty"};
        }
        if (content != offset) {
            // Anchored: PyYAML's mark is the anchor's.
            node.text = word;
            node.position = source_.position(offset);
        } else if (!word.empty() && (key || !source_.colon_follows(offset + word.size()))) {
            check_value_indent(offset);
            node.text = word;
            node.position = source_.position(offset);
        } else {
            // An empty scalar: yaml-cpp marks the token after it, PyYAML the end of the
            // indicator before it.
            char indicator = 0;
            if (!stack_.empty()) {
                const Node& parent = nodes[stack_.back()];
                if (parent.kind == Node::Kind::mapping && !key) indicator = ':';
                if (parent.kind == Node::Kind::sequence) indicator = '-';
            }
            const std::size_t at =
                indicator != 0 ? source_.after_indicator(offset, indicator) : offset;
            node.position = source_.position(at);
        }
        add(std::move(node), anchor, false);
    }

    void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
        check_depth(mark);
        note_key(source_.offset(mark));
        if (anchor >= anchors_.size() || !anchors_[anchor].has_value()) {
            throw SyntaxError{source_.position(mark), "found undefined alias"};
        }
        attach(*anchors_[anchor]);
    }

    void OnScalar(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                  const std::string& value) override {
        check_depth(mark);
        const std::size_t offset = source_.offset(mark);
        if (tag != "?" && tag != "!") throw tag_error(mark, tag);
        check_no_tag(mark, offset);
        const char first = source_.at(source_.skip_properties(offset));
        if (tag == "?" || (first != '|' && first != '>')) {
            check_value_indent(offset);  // a block scalar cannot be a key: it may sit there
        }
        if (tag == "?" && !open_.empty() && open_.back().flow) {
            // In a flow collection PyYAML does not start a plain scalar with ':' or '?'.
            const std::size_t content = source_.skip_properties(offset);
            if (source_.at(content) == ':' || source_.at(content) == '?') {
                throw SyntaxError{source_.position(content),
                                  std::string("expected the node content, but found '") +
                                      source_.at(content) + "'"};
            }
        }
        note_key(offset);
        Node node;
        node.kind = Node::Kind::scalar;
        node.plain = tag == "?";
        node.text = node.plain ? value : repair_escapes(value);
        node.position = source_.position(mark);
        if (!node.plain) non_plain_starts.push_back(source_.skip_properties(offset));
        add(std::move(node), anchor, false);
    }

    void OnSequenceStart(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                         YAML::EmitterStyle::value style) override {
        start_collection(mark, tag, anchor, Node::Kind::sequence, style);
    }
    void OnSequenceEnd() override { end_collection(); }

    void OnMapStart(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                    YAML::EmitterStyle::value style) override {
        start_collection(mark, tag, anchor, Node::Kind::mapping, style);
    }
    void OnMapEnd() override { end_collection(); }

private:
    void check_depth(const YAML::Mark& mark) const {
        if (stack_.size() + 1 > static_cast<std::size_t>(kMaxYamlDepth)) {
            throw SyntaxError{source_.position(mark),
                              "nested deeper than " + std::to_string(kMaxYamlDepth) + " levels"};
        }
    }

    SyntaxError tag_error(const YAML::Mark& mark, const std::string& tag) const {
        return SyntaxError{source_.position(mark),
                           "tags are not supported in a mission file (found '" + tag + "')"};
    }

    // yaml-cpp reports the non-specific tag `!` like a quoted scalar, and reports no tag
    // at all on null scalars: look at the text.
    void check_no_tag(const YAML::Mark& mark, std::size_t offset) const {
        std::size_t at = offset;
        for (int guard = 0; guard < 2; ++guard) {
            if (source_.at(at) == '!') throw tag_error(mark, "!");
            if (source_.at(at) != '&') return;
            while (at < source_.size() && source_.at(at) != ' ' && source_.at(at) != '\t' &&
                   source_.at(at) != '\n') {
                ++at;
            }
            at = source_.skip_blanks(at);
        }
    }

    bool in_key_slot() const {
        if (stack_.empty()) return false;
        const Node& parent = nodes[stack_.back()];
        return parent.kind == Node::Kind::mapping && parent.children.size() % 2 == 0;
    }

    // yaml-cpp accepts entries PyYAML refuses: in a block mapping, one without a key
    // (`: value`) and a plain key without its ':'; in a flow collection, an empty entry
    // (`[a, , b]`). The first arrives as a null key marked at the ':', the second as a
    // null value marked where its key is, the third as a null marked at the ','.
    void check_entry(std::size_t offset) const {
        if (stack_.empty()) return;
        const Node& parent = nodes[stack_.back()];
        if (open_.back().flow) {
            const char c = source_.at(offset);
            if ((parent.kind == Node::Kind::sequence || in_key_slot()) && c == ',') {
                throw SyntaxError{source_.position(offset),
                                  "expected the node content, but found ','"};
            }
            if (in_key_slot() && c == ':') {
                throw SyntaxError{source_.position(offset),
                                  "expected the node content, but found ':'"};
            }
            return;
        }
        if (parent.kind != Node::Kind::mapping) return;
        if (in_key_slot()) {
            if (source_.at(offset) == ':') {
                throw SyntaxError{source_.position(offset), "expected <block end>, but found ':'"};
            }
        } else if (offset == open_.back().key_offset && source_.at(offset) != '?') {
            throw SyntaxError{source_.position(offset), "could not find expected ':'"};
        }
    }

    void note_key(std::size_t offset) {
        if (in_key_slot()) open_.back().key_offset = offset;
    }

    // A block mapping's value on a line after its key must be indented deeper than the
    // key (yaml-cpp also takes one at the key's column; PyYAML reads that as a new key).
    void check_value_indent(std::size_t offset) const {
        if (stack_.empty() || open_.back().flow || in_key_slot()) return;
        if (nodes[stack_.back()].kind != Node::Kind::mapping) return;
        if (open_.back().key_offset == kNoOffset) return;
        const std::size_t after_colon = source_.after_indicator(offset, ':');
        if (after_colon == offset || source_.line_start(after_colon - 1) == source_.line_start(offset)) {
            return;  // on the line of its ':'
        }
        const Position key = source_.position(open_.back().key_offset);
        const Position value = source_.position(offset);
        if (value.col <= key.col) {
            throw SyntaxError{value, "could not find expected ':'"};
        }
    }

    void start_collection(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                          Node::Kind kind, YAML::EmitterStyle::value style) {
        check_depth(mark);
        if (tag != "?") throw tag_error(mark, tag);
        check_no_tag(mark, source_.offset(mark));
        if (style == YAML::EmitterStyle::Flow) check_value_indent(source_.offset(mark));
        note_key(source_.offset(mark));
        Node node;
        node.kind = kind;
        node.position = source_.position(mark);
        add(std::move(node), anchor, true);
        open_.push_back(Open{style == YAML::EmitterStyle::Flow, kNoOffset});
    }

    void end_collection() {
        assert(!stack_.empty() && open_.size() == stack_.size());
        stack_.pop_back();
        open_.pop_back();
    }

    void add(Node node, YAML::anchor_t anchor, bool open) {
        const auto index = static_cast<std::uint32_t>(nodes.size());
        nodes.push_back(std::move(node));
        if (anchor != YAML::NullAnchor) {
            if (anchors_.size() <= anchor) anchors_.resize(anchor + 1);
            anchors_[anchor] = index;
        }
        attach(index);
        if (open) stack_.push_back(index);
    }

    void attach(std::uint32_t index) {
        if (stack_.empty()) {
            if (!root) root = index;
            return;
        }
        nodes[stack_.back()].children.push_back(index);
    }

    static constexpr std::size_t kNoOffset = static_cast<std::size_t>(-1);
    // What is known of each open collection, parallel to `stack_`.
    struct Open {
        bool flow = false;
        std::size_t key_offset = kNoOffset;  // mappings: where the current entry's key is
    };

    const Source& source_;
    std::vector<std::uint32_t> stack_;
    std::vector<Open> open_;
    std::vector<std::optional<std::uint32_t>> anchors_;
    std::unordered_set<std::string> anchor_names_;
};

// Consumes a further document without building anything.
class IgnoreEvents final : public YAML::EventHandler {
public:
    YAML::Mark start;  // where the document starts

    void OnDocumentStart(const YAML::Mark& mark) override { start = mark; }
    void OnDocumentEnd() override {}
    void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
    void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
    void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  const std::string&) override {}
    void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                         YAML::EmitterStyle::value) override {}
    void OnSequenceEnd() override {}
    void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                    YAML::EmitterStyle::value) override {}
    void OnMapEnd() override {}
};

// ------------------------------------------------------------------------------------
// Tabs: PyYAML accepts a tab only inside a quoted scalar, a block scalar's text, or a
// comment; yaml-cpp accepts more. Refuse what PyYAML refuses.

struct Extent {
    std::size_t begin = 0;
    std::size_t end = 0;     // exclusive
    std::size_t indent = 0;  // block scalars: a tab must come after this many columns
    bool block = false;
    bool closed = true;  // quoted scalars: the closing quote was found
};

Extent scalar_extent(const Source& source, std::size_t start) {
    Extent extent{start, start, 0, false, true};
    const char opener = source.at(start);
    std::size_t i = start + 1;
    if (opener == '\'' || opener == '"') {
        extent.closed = false;
        while (i < source.size()) {
            const char c = source.at(i);
            if (opener == '"' && c == '\\') {
                i += 2;
                continue;
            }
            if (c == opener) {
                if (opener == '\'' && source.at(i + 1) == '\'') {
                    i += 2;
                    continue;
                }
                ++i;
                extent.closed = true;
                break;
            }
            ++i;
        }
        extent.end = std::min(i, source.size());
    } else if (opener == '|' || opener == '>') {
        // The header line is not part of the text; the text is the following lines
        // indented deeper than the header's line, up to the first one that is not.
        const std::size_t header_start = source.line_start(start);
        std::size_t header_indent = 0;
        while (source.at(header_start + header_indent) == ' ') ++header_indent;
        std::size_t line = start;
        while (line < source.size() && source.at(line) != '\n') ++line;
        line = std::min(line + 1, source.size());
        extent.begin = line;
        extent.block = true;
        std::optional<std::size_t> indent;
        while (line < source.size()) {
            std::size_t spaces = 0;
            while (source.at(line + spaces) == ' ') ++spaces;
            const char first = source.at(line + spaces);
            const bool blank = first == '\n' || line + spaces >= source.size();
            if (!blank) {
                if (!indent) {
                    if (spaces <= header_indent) break;
                    indent = spaces;
                } else if (spaces < *indent) {
                    break;
                }
            }
            while (line < source.size() && source.at(line) != '\n') ++line;
            line = std::min(line + 1, source.size());
        }
        extent.end = line;
        extent.indent = indent.value_or(header_indent + 1);
    }
    return extent;
}

// Also refuses a quoted scalar that runs to the end of the text, which yaml-cpp accepts.
void check_scalars_and_tabs(const Source& source, const std::vector<std::size_t>& non_plain_starts) {
    const std::string& text = source.buffer();
    std::vector<Extent> extents;
    extents.reserve(non_plain_starts.size());
    for (std::size_t start : non_plain_starts) {
        extents.push_back(scalar_extent(source, start));
        if (!extents.back().closed) {
            throw SyntaxError{source.position(source.size()), "found unexpected end of stream"};
        }
    }
    if (text.find('\t') == std::string::npos) return;
    std::sort(extents.begin(), extents.end(),
              [](const Extent& a, const Extent& b) { return a.begin < b.begin; });
    // Scalars do not overlap and come in file order: find the one holding `offset` by
    // bisection.
    auto inside = [&](std::size_t offset) -> const Extent* {
        auto it = std::upper_bound(extents.begin(), extents.end(), offset,
                                   [](std::size_t o, const Extent& e) { return o < e.begin; });
        if (it == extents.begin()) return nullptr;
        --it;
        return offset < it->end ? &*it : nullptr;
    };
    std::size_t comment_line = static_cast<std::size_t>(-1);  // the line whose comment...
    std::size_t comment_from = 0;                              // ...starts here
    for (std::size_t t = text.find('\t'); t != std::string::npos; t = text.find('\t', t + 1)) {
        const std::size_t line = source.line_start(t);
        if (const Extent* e = inside(t)) {
            if (!e->block || t - line >= e->indent) continue;
        }
        if (line == comment_line && comment_from < t) continue;
        bool comment = false;
        for (std::size_t h = line; h < t && !comment; ++h) {
            if (text[h] == '#' && source.starts_token(h) && inside(h) == nullptr) {
                comment = true;
                comment_line = line;
                comment_from = h;
            }
        }
        if (!comment) {
            throw SyntaxError{source.position(t),
                              "found character '\\t' that cannot start any token"};
        }
    }
}

// ------------------------------------------------------------------------------------
// Scalars: the YAML 1.2 core schema, as mission.py's `_scalar`

bool all_digits(std::string_view s) {
    return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

std::string_view strip_sign(std::string_view s) {
    if (!s.empty() && (s[0] == '-' || s[0] == '+')) s.remove_prefix(1);
    return s;
}

bool is_int(std::string_view s) { return all_digits(strip_sign(s)); }

// ^[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?$
bool is_float(std::string_view s) {
    s = strip_sign(s);
    std::size_t i = 0;
    auto digits = [&] {
        const std::size_t from = i;
        while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
        return i - from;
    };
    if (i < s.size() && s[i] == '.') {
        ++i;
        if (digits() == 0) return false;
    } else {
        if (digits() == 0) return false;
        if (i < s.size() && s[i] == '.') {
            ++i;
            digits();
        }
    }
    if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
        ++i;
        if (i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
        if (digits() == 0) return false;
    }
    return i == s.size();
}

bool is_inf(std::string_view s) {
    s = strip_sign(s);
    return s == ".inf" || s == ".Inf" || s == ".INF";
}

bool is_nan(std::string_view s) { return s == ".nan" || s == ".NaN" || s == ".NAN"; }

// The integer as Python prints int(text).
std::string canonical_integer(std::string_view text) {
    const bool negative = !text.empty() && text[0] == '-';
    std::string_view digits = strip_sign(text);
    while (digits.size() > 1 && digits[0] == '0') digits.remove_prefix(1);
    if (digits == "0") return "0";
    return (negative ? "-" : "") + std::string(digits);
}

// ------------------------------------------------------------------------------------
// Plain data from the node graph, as mission.py's `_Document.convert`

struct TooLarge {};
struct Cyclic {
    Position position;
};
struct TooDeep {
    Position position;
};

class Converter {
public:
    Converter(const std::vector<Node>& nodes, const std::string& file,
              std::vector<LoadError>& errors)
        : nodes_(nodes), file_(file), errors_(errors), active_(nodes.size(), false) {}

    // The first pass only counts and looks for cycles and depth, in the same order as the
    // second, so that refused documents are refused before anything is allocated.
    void count(std::uint32_t index, int depth) {
        enter(index, depth);
        const Node& node = nodes_[index];
        if (node.kind == Node::Kind::scalar) return;
        active_[index] = true;
        if (node.kind == Node::Kind::sequence) {
            for (std::uint32_t child : node.children) count(child, depth + 1);
        } else {
            std::unordered_set<std::string> seen;
            for (std::size_t i = 0; i + 1 < node.children.size(); i += 2) {
                const Node& key = nodes_[node.children[i]];
                if (key.kind != Node::Kind::scalar) continue;
                if (!seen.insert(key.text).second) continue;
                count(node.children[i + 1], depth + 1);
            }
        }
        active_[index] = false;
    }

    Value convert(std::uint32_t index) {
        const Node& node = nodes_[index];
        Value value;
        value.position = node.position;
        switch (node.kind) {
            case Node::Kind::scalar:
                type_scalar(node, value);
                break;
            case Node::Kind::sequence:
                value.type = Value::Type::list;
                value.items.reserve(node.children.size());
                for (std::uint32_t child : node.children) value.items.push_back(convert(child));
                break;
            case Node::Kind::mapping: {
                value.type = Value::Type::mapping;
                std::unordered_set<std::string> seen;
                for (std::size_t i = 0; i + 1 < node.children.size(); i += 2) {
                    const Node& key = nodes_[node.children[i]];
                    if (key.kind != Node::Kind::scalar) {
                        error(key.position, "wrong-type", "a mapping key must be a scalar");
                        continue;
                    }
                    if (!seen.insert(key.text).second) {
                        error(key.position, "duplicate-key", "duplicate key '" + key.text + "'");
                        continue;
                    }
                    value.keys.push_back(key.text);
                    value.key_positions.push_back(key.position);
                    value.items.push_back(convert(node.children[i + 1]));
                }
                break;
            }
        }
        return value;
    }

private:
    void enter(std::uint32_t index, int depth) {
        if (++count_ > kMaxYamlNodes) throw TooLarge{};
        const Node& node = nodes_[index];
        if (active_[index]) throw Cyclic{node.position};
        if (depth > kMaxYamlDepth) throw TooDeep{node.position};
    }

    void type_scalar(const Node& node, Value& value) {
        const std::string& text = node.text;
        value.type = Value::Type::string;
        value.string = text;
        if (!node.plain) return;
        if (text.empty() || text == "~" || text == "null" || text == "Null" || text == "NULL") {
            value.type = Value::Type::null;
        } else if (text == "true" || text == "True" || text == "TRUE") {
            value.type = Value::Type::boolean;
            value.boolean = true;
        } else if (text == "false" || text == "False" || text == "FALSE") {
            value.type = Value::Type::boolean;
            value.boolean = false;
        } else if (is_int(text)) {
            value.type = Value::Type::integer;
            std::string_view digits = text;
            if (!digits.empty() && digits[0] == '+') digits.remove_prefix(1);
            const auto [end, status] =
                std::from_chars(digits.data(), digits.data() + digits.size(), value.integer);
            if (status != std::errc() || end != digits.data() + digits.size()) {
                error(node.position, "out-of-range",
                      "the integer " + canonical_integer(text) + " does not fit in 64 bits");
            }
        } else if (is_float(text)) {
            value.type = Value::Type::number;
            value.number = std::strtod(text.c_str(), nullptr);
        } else if (is_inf(text)) {
            value.type = Value::Type::number;
            value.number = text[0] == '-' ? -HUGE_VAL : HUGE_VAL;
        } else if (is_nan(text)) {
            value.type = Value::Type::number;
            value.number = std::nan("");
        }
    }

    void error(Position position, std::string rule, std::string message) {
        errors_.push_back(LoadError{file_, position.line, position.col, std::move(rule),
                                    std::move(message)});
    }

    const std::vector<Node>& nodes_;
    const std::string& file_;
    std::vector<LoadError>& errors_;
    std::vector<bool> active_;
    std::int64_t count_ = 0;
};

// Code points of UTF-8 text (already validated).
template <typename Visit>
void for_each_code_point(std::string_view text, Visit visit) {
    std::size_t i = 0;
    while (i < text.size()) {
        const auto b0 = static_cast<unsigned char>(text[i]);
        char32_t cp = 0;
        std::size_t length = 1;
        if (b0 < 0x80) {
            cp = b0;
        } else if (b0 < 0xE0) {
            cp = b0 & 0x1Fu;
            length = 2;
        } else if (b0 < 0xF0) {
            cp = b0 & 0x0Fu;
            length = 3;
        } else {
            cp = b0 & 0x07u;
            length = 4;
        }
        for (std::size_t k = 1; k < length && i + k < text.size(); ++k) {
            cp = (cp << 6) | (static_cast<unsigned char>(text[i + k]) & 0x3Fu);
        }
        if (!visit(i, cp)) return;
        i += length;
    }
}

bool printable(char32_t cp) {
    // PyYAML's Reader: tab, LF, CR, printable ASCII, NEL, and the BMP/astral ranges.
    return cp == 0x09 || cp == 0x0A || cp == 0x0D || (cp >= 0x20 && cp <= 0x7E) || cp == 0x85 ||
           (cp >= 0xA0 && cp <= 0xD7FF) || (cp >= 0xE000 && cp <= 0xFFFD) ||
           (cp >= 0x10000 && cp <= 0x10FFFF);
}

std::string hex4(char32_t cp) {
    char buffer[16];
    std::snprintf(buffer, sizeof buffer, "%04x", static_cast<unsigned>(cp));
    return buffer;
}

std::string upper_hex4(char32_t cp) {
    char buffer[16];
    std::snprintf(buffer, sizeof buffer, "%04X", static_cast<unsigned>(cp));
    return buffer;
}

}  // namespace

// --------------------------------------------------------------------------------------

const Value* Value::get(std::string_view key) const {
    for (std::size_t i = 0; i < keys.size(); ++i) {
        if (keys[i] == key) return &items[i];
    }
    return nullptr;
}

Position Value::key_position(std::string_view key) const {
    for (std::size_t i = 0; i < keys.size(); ++i) {
        if (keys[i] == key) return key_positions[i];
    }
    return position;
}

std::optional<std::size_t> first_invalid_utf8(std::string_view bytes) {
    std::size_t i = 0;
    auto byte = [&](std::size_t k) { return static_cast<unsigned char>(bytes[k]); };
    auto in = [&](std::size_t k, unsigned lo, unsigned hi) {
        return k < bytes.size() && byte(k) >= lo && byte(k) <= hi;
    };
    while (i < bytes.size()) {
        const unsigned b0 = byte(i);
        std::size_t length = 0;
        if (b0 < 0x80) {
            length = 1;
        } else if (b0 >= 0xC2 && b0 <= 0xDF) {
            length = in(i + 1, 0x80, 0xBF) ? 2 : 0;
        } else if (b0 == 0xE0) {
            length = in(i + 1, 0xA0, 0xBF) && in(i + 2, 0x80, 0xBF) ? 3 : 0;
        } else if ((b0 >= 0xE1 && b0 <= 0xEC) || b0 == 0xEE || b0 == 0xEF) {
            length = in(i + 1, 0x80, 0xBF) && in(i + 2, 0x80, 0xBF) ? 3 : 0;
        } else if (b0 == 0xED) {
            length = in(i + 1, 0x80, 0x9F) && in(i + 2, 0x80, 0xBF) ? 3 : 0;
        } else if (b0 == 0xF0) {
            length = in(i + 1, 0x90, 0xBF) && in(i + 2, 0x80, 0xBF) && in(i + 3, 0x80, 0xBF) ? 4 : 0;
        } else if (b0 >= 0xF1 && b0 <= 0xF3) {
            length = in(i + 1, 0x80, 0xBF) && in(i + 2, 0x80, 0xBF) && in(i + 3, 0x80, 0xBF) ? 4 : 0;
        } else if (b0 == 0xF4) {
            length = in(i + 1, 0x80, 0x8F) && in(i + 2, 0x80, 0xBF) && in(i + 3, 0x80, 0xBF) ? 4 : 0;
        }
        if (length == 0) return i;
        i += length;
    }
    return std::nullopt;
}

std::string python_float_repr(double value) {
    if (std::isnan(value)) return "nan";
    if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
    char buffer[64];
    const auto result =
        std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::scientific);
    std::string text(buffer, result.ptr);  // shortest round-trip digits, e.g. "-1.5e+03"
    const bool negative = text[0] == '-';
    if (negative) text.erase(0, 1);
    const std::size_t e = text.find('e');
    const int exponent = std::atoi(text.c_str() + e + 1);
    std::string digits;
    for (std::size_t i = 0; i < e; ++i) {
        if (text[i] != '.') digits += text[i];
    }
    std::string out;
    if (exponent >= -4 && exponent < 16) {
        const int point = exponent + 1;  // digits before the decimal point
        if (point <= 0) {
            out = "0." + std::string(static_cast<std::size_t>(-point), '0') + digits;
        } else if (static_cast<std::size_t>(point) >= digits.size()) {
            out = digits + std::string(static_cast<std::size_t>(point) - digits.size(), '0') + ".0";
        } else {
            const auto split = static_cast<std::size_t>(point);
            out = digits.substr(0, split) + "." + digits.substr(split);
        }
    } else {
        out = digits.substr(0, 1);
        if (digits.size() > 1) out += "." + digits.substr(1);
        char exponent_text[16];
        std::snprintf(exponent_text, sizeof exponent_text, "e%c%02d", exponent < 0 ? '-' : '+',
                      std::abs(exponent));
        out += exponent_text;
    }
    return negative ? "-" + out : out;
}

std::optional<Value> parse_yaml(const std::string& text, const std::string& file,
                                std::vector<LoadError>& errors) {
    auto fail = [&](Position position, std::string message) -> std::optional<Value> {
        errors.push_back(
            LoadError{file, position.line, position.col, "yaml-syntax", std::move(message)});
        return std::nullopt;
    };
    if (text.size() > kMaxFileBytes) {
        return fail({1, 1}, "the mission file is larger than " +
                                std::to_string(kMaxFileBytes / (1024 * 1024)) + " MiB");
    }
    const Source source(text);

    // Characters PyYAML refuses, or reads differently from yaml-cpp.
    std::optional<Value> refused;
    bool stop = false;
    for_each_code_point(text, [&](std::size_t offset, char32_t cp) {
        if (cp == 0x85 || cp == 0x2028 || cp == 0x2029) {
            refused = fail(source.position(offset), "line break character U+" + upper_hex4(cp) +
                                                        " is not supported (use LF or CRLF)");
            stop = true;
            return false;
        }
        return true;
    });
    if (stop) return refused;
    for_each_code_point(text, [&](std::size_t offset, char32_t cp) {
        if (!printable(cp)) {
            refused = fail(source.position(offset), "unacceptable character #x" + hex4(cp) +
                                                        ": special characters are not allowed");
            stop = true;
            return false;
        }
        return true;
    });
    if (stop) return refused;

    GraphBuilder builder(source);
    try {
        std::istringstream stream(source.buffer());
        YAML::Parser parser(stream);
        if (!parser.HandleNextDocument(builder) || !builder.root) {
            return fail({1, 1}, "the mission file is empty");
        }
        // yaml-cpp reads a text that starts with "..." as an empty document; PyYAML finds
        // no document content there.
        const std::size_t first = source.skip_blanks(source.offset(YAML::Mark()));
        if (source.buffer().compare(first, 3, "...") == 0 &&
            (first + 3 >= source.size() || std::isspace(static_cast<unsigned char>(source.at(first + 3))))) {
            return fail(source.position(first),
                        "expected the node content, but found '<document end>'");
        }
        check_scalars_and_tabs(source, builder.non_plain_starts);
        IgnoreEvents ignore;
        if (parser.HandleNextDocument(ignore)) {
            return fail(source.position(ignore.start), "expected a single document in the stream");
        }
    } catch (const SyntaxError& error) {
        return fail(error.position, error.message);
    } catch (const YAML::Exception& error) {
        return fail(source.position(error.mark), error.msg);
    } catch (const std::exception& error) {
        return fail({1, 1}, std::string("not valid YAML: ") + error.what());
    }

    Converter converter(builder.nodes, file, errors);
    try {
        converter.count(*builder.root, 1);
    } catch (const Cyclic& cyclic) {
        return fail(cyclic.position, "cyclic alias");
    } catch (const TooDeep& deep) {
        return fail(deep.position,
                    "nested deeper than " + std::to_string(kMaxYamlDepth) + " levels");
    } catch (const TooLarge&) {
        return fail({1, 1}, "more than " + std::to_string(kMaxYamlNodes) + " YAML nodes");
    }
    const std::size_t before = errors.size();
    Value value = converter.convert(*builder.root);
    if (errors.size() != before) return std::nullopt;
    return value;
}

}  // namespace keel::mission::detail
