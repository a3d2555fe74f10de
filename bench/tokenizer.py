"""Qwen3's tokenizer vs byte-level BPEs learned on our texts: which trains a from-scratch model faster.

Run: python3 -m bench.tokenizer [--objects 500] [--vocab 1024 4096 16384] [--digits 1 3] [--image-size 448]

Texts come straight from the factories (no rendering): for each object, at rest, the stage-2
prompt (build_prompt), the target JSON (canonical structure with extracted relations, as
`jax3dc data build` writes for view 0) and the part program. Objects are split as the
datasets are (data_pipeline.samples.split_of): BPEs learn from the train split of all but the
--unseen categories and are measured on the held-out objects (val + test) of the other
categories, and separately on every object of the unseen categories (how a BPE copes with
words it never saw).

Per tokenizer it prints tokens per prompt / target / program (mean and p95), whether
decode(encode(x)) == x for every held-out text (and the rendered conversations with their
special tokens), and for the `small` preset (hidden 512, tied embeddings) the embedding
parameters the vocabulary implies and the training FLOPs of one example, 6 x parameters x
positions, where every position goes through the decoder and the LM head (logits are made at
every position) and the vision tower's patches add the same for every tokenizer; attention
scores are left out. A structure example is I + S + prompt + target, a code example I +
CODE_PROMPT + program. The recommendation at the end follows from these figures (rule in
recommend()).
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass

import numpy as np

from data_pipeline.samples import split_of
from jax3dc.factories import FACTORIES, generate_object
from jax3dc.geometry.parts import part_boxes
from jax3dc.processing.bpe import chat_segments, config_for_tokenizer, train_bpe
from jax3dc.processing.chat import render_chat
from jax3dc.model.config import Qwen3VLConfig
from jax3dc.model.params import abstract_model, param_count
from jax3dc.processing.tokenizer import Tokenizer, load_tokenizer
from jax3dc.palette import object_palette
from jax3dc.prompt import build_prompt, chat_messages, code_messages
from jax3dc.relations import with_extracted_relations
from jax3dc.structure import canonicalize, to_json

#: Every tenth category is held out of BPE training entirely.
DEFAULT_UNSEEN = tuple(list(FACTORIES)[9::10])


@dataclass(frozen=True)
class Sample:
    category: str
    split: str
    prompt: str
    target: str
    program: str


def make_samples(objects: int) -> list[Sample]:
    """``objects`` factory objects, categories in turn, seeds 0, 1, ... per category."""
    categories = list(FACTORIES)
    out = []
    for i in range(objects):
        category, seed = categories[i % len(categories)], i // len(categories)
        obj = generate_object(category, seed)
        boxes = part_boxes(obj.parts)
        structure = canonicalize(with_extracted_relations(obj.structure, obj.parts), boxes)
        prompt = build_prompt(boxes, object_palette(category, obj.object_id), len(structure.joints()) or None)
        out.append(Sample(category, split_of(obj.object_id), prompt, to_json(structure), obj.program_text))
    return out


def training_texts(samples: list[Sample]) -> list[str]:
    texts = []
    for s in samples:
        texts += chat_segments(chat_messages(s.prompt, s.target)) + chat_segments(code_messages(s.program))
    return texts


def stats(values: list[int]) -> tuple[float, float]:
    return float(np.mean(values)), float(np.percentile(values, 95))


@dataclass(frozen=True)
class Cost:
    """Parameters and FLOPs of the `small` preset sized to a tokenizer."""

    vocab_rows: int
    embedding: int
    total: int
    decoder: int  # text decoder without the embedding
    vision_patch: int  # vision parameters applied at every patch
    vision_merged: int  # mergers, applied at every merged (LLM) token

    def flops(self, text_tokens: float, images: int, patches_per_image: int, merged_per_image: int) -> float:
        positions = text_tokens + images * merged_per_image
        return 6.0 * ((self.decoder + self.embedding) * positions + self.vision_patch * images * patches_per_image
                      + self.vision_merged * images * merged_per_image)


def small_cost(tokenizer: Tokenizer) -> Cost:
    config = config_for_tokenizer(Qwen3VLConfig.small(), tokenizer)
    model = abstract_model(config)
    embedding = param_count(model, "language_model.embed_tokens")
    mergers = param_count(model, "visual.merger") + param_count(model, "visual.deepstack_merger_list")
    patchwise = param_count(model, "visual.blocks") + param_count(model, "visual.patch_embed")
    return Cost(config.text.vocab_size, embedding, param_count(model),
                param_count(model, "language_model") - embedding, patchwise, mergers)


def measure(name: str, tokenizer: Tokenizer, held_out: list[Sample], unseen: list[Sample],
            image_size: int) -> dict:
    count = lambda text: len(tokenizer.encode(text))
    row = {"name": name, "ids": tokenizer.vocab_size}
    for field in ("prompt", "target", "program"):
        row[field] = stats([count(getattr(s, field)) for s in held_out])
        row[f"unseen_{field}"] = stats([count(getattr(s, field)) for s in unseen])
    exact = total = 0
    for s in held_out + unseen:
        chats = [render_chat(chat_messages(s.prompt, s.target), [3, 3])[0],
                 render_chat(code_messages(s.program), [3])[0]]
        for text in (s.prompt, s.target, s.program):
            exact += tokenizer.decode(tokenizer.encode(text)) == text
        for text in chats:
            exact += tokenizer.decode(tokenizer.encode(text), skip_special_tokens=False) == text
        total += 5
    row["round_trip"] = (exact, total)
    structure_text = np.mean([count(render_chat(chat_messages(s.prompt, s.target), [0, 0])[0]) for s in held_out])
    code_text = np.mean([count(render_chat(code_messages(s.program), [0])[0]) for s in held_out])
    cost = small_cost(tokenizer)
    config = Qwen3VLConfig.small()
    patches = (image_size // config.vision.patch_size) ** 2
    merged = patches // config.vision.spatial_merge_size**2
    row.update(cost=cost, structure_tokens=structure_text + 2 * merged, code_tokens=code_text + merged,
               structure_flops=cost.flops(structure_text, 2, patches, merged),
               code_flops=cost.flops(code_text, 1, patches, merged))
    return row


def print_table(rows: list[dict]) -> None:
    f = lambda pair: f"{pair[0]:.0f} / {pair[1]:.0f}"
    print("\nHeld-out objects of seen categories (tokens: mean / p95):")
    print("| tokenizer | ids | prompt | target JSON | program | round trip | struct. example | code example |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['name']} | {r['ids']:,} | {f(r['prompt'])} | {f(r['target'])} | {f(r['program'])} | "
              f"{r['round_trip'][0]}/{r['round_trip'][1]} | {r['structure_tokens']:.0f} | {r['code_tokens']:.0f} |")
    base = rows[0]
    print("\nUnseen categories (BPEs never saw them; tokens mean / p95, and mean relative to Qwen3):")
    print("| tokenizer | prompt | target JSON | program |")
    print("|---|---|---|---|")
    for r in rows:
        cells = [f"{f(r['unseen_' + k])} ({r['unseen_' + k][0] / base['unseen_' + k][0]:.2f}x)"
                 for k in ("prompt", "target", "program")]
        print(f"| {r['name']} | " + " | ".join(cells) + " |")
    print("\n`small` preset (hidden 512, tied LM head) sized to each tokenizer; training FLOPs per example "
          "= 6 x params x positions (decoder + LM head at every position, vision tower per patch):")
    print("| tokenizer | vocab rows | embedding params | total params | GFLOP / structure ex. | GFLOP / code ex. "
          "| vs Qwen3 (structure) |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        c = r["cost"]
        print(f"| {r['name']} | {c.vocab_rows:,} | {c.embedding / 1e6:.2f} M | {c.total / 1e6:.1f} M | "
              f"{r['structure_flops'] / 1e9:.0f} | {r['code_flops'] / 1e9:.0f} | "
              f"{r['structure_flops'] / base['structure_flops']:.2f}x |")


def recommend(rows: list[dict], asked: dict[str, int]) -> list[str]:
    """Lines of advice from the figures: among BPEs that keep Qwen3's split (one digit per token),
    round-trip every held-out text and do not inflate unseen-category targets by more than 25 %,
    the one with the fewest FLOPs per structure+code example pair; digit runs are reported
    beside it, not chosen, since they change how numbers are tokenized and only a learning run
    can say whether that helps."""
    cost = lambda r: r["structure_flops"] + r["code_flops"]
    base = rows[0]
    ok = [r for r in rows[1:] if r["round_trip"][0] == r["round_trip"][1]
          and r["unseen_target"][0] <= 1.25 * base["unseen_target"][0]]
    lines = []
    saturated = sorted({r["ids"] for r in rows[1:] if r["ids"] < asked[r["name"]]})
    if saturated:
        lines.append(f"Learned vocabularies stop at {', '.join(map(str, saturated))} ids whatever size is asked: "
                     "no pair seen twice in the training text is left to merge, so larger sizes change nothing.")
    plain = [r for r in ok if "digits" not in r["name"]]
    if not plain:
        return lines + ["Recommendation: keep Qwen3's tokenizer (no BPE round-trips exactly and covers unseen "
                        "categories)."]
    best = min(plain, key=lambda r: (round(cost(r) / 1e9), r["ids"]))
    lines.append(
        f"Recommendation: {best['name']} ({best['ids']:,} ids) for models trained from scratch: "
        f"{cost(best) / cost(base):.2f}x the training FLOPs of Qwen3's tokenizer per structure+code example "
        f"({best['structure_tokens']:.0f} vs {base['structure_tokens']:.0f} positions per structure example), "
        f"{best['cost'].total / 1e6:.1f} M vs {base['cost'].total / 1e6:.1f} M parameters in `small`, exact round "
        f"trip {best['round_trip'][0]}/{best['round_trip'][1]}, unseen-category targets "
        f"{best['unseen_target'][0] / base['unseen_target'][0]:.2f}x Qwen3's tokens. Keep Qwen3's tokenizer when "
        "fine-tuning a Qwen3-VL checkpoint.")
    grouped = [r for r in ok if "digits" in r["name"]]
    if grouped:
        g = min(grouped, key=lambda r: (round(cost(r) / 1e9), r["ids"]))
        lines.append(f"Digit runs ({g['name']}) would save a further {1 - cost(g) / cost(best):.0%} of FLOPs "
                     f"({g['structure_tokens']:.0f} positions per structure example) but tokenize numbers "
                     "differently from Qwen3; compare the two in a learning run before switching.")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--objects", type=int, default=500, help="factory objects (default 500)")
    parser.add_argument("--vocab", type=int, nargs="+", default=[1024, 4096, 16384], help="BPE sizes, ids in all")
    parser.add_argument("--digits", type=int, nargs="+", default=[1, 3],
                        help="longest digit run per token, one BPE per value (Qwen3: 1; default 1 3)")
    parser.add_argument("--unseen", nargs="*", default=list(DEFAULT_UNSEEN), help="categories kept out of training")
    parser.add_argument("--image-size", type=int, default=448, help="side of I and S in pixels (default 448)")
    args = parser.parse_args()

    start = time.perf_counter()
    samples = make_samples(args.objects)
    unseen = [s for s in samples if s.category in args.unseen]
    seen = [s for s in samples if s.category not in args.unseen]
    train = [s for s in seen if s.split == "train"]
    held_out = [s for s in seen if s.split != "train"]
    print(f"{len(samples)} objects of {len(FACTORIES)} categories in {time.perf_counter() - start:.0f} s: "
          f"{len(train)} train, {len(held_out)} held out, {len(unseen)} of unseen categories {args.unseen}")
    texts = training_texts(train)
    print(f"BPE training text: {sum(map(len, texts)) / 1e6:.2f} M characters in {len(texts)} segments")
    tokenizers = [("Qwen3", load_tokenizer())]
    asked = {}
    for digits in args.digits:
        for size in args.vocab:
            name = f"BPE {size}" + ("" if digits == 1 else f", digits<={digits}")
            asked[name] = size
            start = time.perf_counter()
            tokenizers.append((name, train_bpe(texts, size, digits=digits)))
            print(f"{name}: {tokenizers[-1][1].vocab_size} ids, trained in {time.perf_counter() - start:.1f} s")
    rows = [measure(name, tok, held_out, unseen, args.image_size) for name, tok in tokenizers]
    print_table(rows)
    print("\n" + "\n".join(recommend(rows, asked)))


if __name__ == "__main__":
    main()
