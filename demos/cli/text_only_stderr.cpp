#include "text_only_stderr.h"

#include <cstdio>
#include <iostream>

namespace torsion::cli {

TextOnlyStderr::TextOnlyStderr() : original_(std::cerr.rdbuf()), filter_(original_) {
  std::cerr.rdbuf(&filter_);
}

TextOnlyStderr::~TextOnlyStderr() {
  filter_.flushPending();
  std::cerr.rdbuf(original_);
}

void TextOnlyStderr::Filter::escape(unsigned char byte) {
  char text[8];
  std::snprintf(text, sizeof text, "\\x%02X", static_cast<unsigned>(byte));
  target_->sputn(text, 4);
}

void TextOnlyStderr::Filter::flushPending() {
  for (const char c : pending_)
    escape(static_cast<unsigned char>(c));
  pending_.clear();
  needed_ = 0;
}

void TextOnlyStderr::Filter::put(unsigned char byte) {
  if (needed_ > 0) {
    if ((byte & 0xC0) == 0x80) {
      pending_ += static_cast<char>(byte);
      if (--needed_ == 0) {
        target_->sputn(pending_.data(), static_cast<std::streamsize>(pending_.size()));
        pending_.clear();
      }
      return;
    }
    flushPending();  // a broken sequence: show its bytes, then read this one afresh
  }
  if (byte < 0x80) {
    const bool text = byte >= 0x20 ? byte != 0x7F : (byte == '\n' || byte == '\t' || byte == '\r');
    if (text) {
      target_->sputc(static_cast<char>(byte));
    } else {
      escape(byte);
    }
    return;
  }
  // Lead bytes of 2, 3 and 4-byte sequences (0xC0, 0xC1 and above 0xF4 never start valid UTF-8).
  if (byte >= 0xC2 && byte <= 0xDF) {
    needed_ = 1;
  } else if (byte >= 0xE0 && byte <= 0xEF) {
    needed_ = 2;
  } else if (byte >= 0xF0 && byte <= 0xF4) {
    needed_ = 3;
  } else {
    escape(byte);
    return;
  }
  pending_.assign(1, static_cast<char>(byte));
}

TextOnlyStderr::Filter::int_type TextOnlyStderr::Filter::overflow(int_type c) {
  if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
  put(static_cast<unsigned char>(traits_type::to_char_type(c)));
  return c;
}

}  // namespace torsion::cli
